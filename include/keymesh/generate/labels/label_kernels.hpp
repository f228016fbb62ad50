#pragma once
// The label generators' per-element work shared by their CPU paths
// (labels_surface_nets.cpp, label_smoothing.cpp) and the device path
// (labels_device.hpp), so that both give the same bits: the surface nets
// network's quad of an edge, a cell's point, the junction test, one
// Jacobi step of the smoothing and its fold guard.
#include <cmath>
#include <cstdint>

#include "keymesh/core/device.hpp"
#include "keymesh/core/types.hpp"

namespace keymesh::generate::label_kernels {

// The four cells around an edge along `axis`, as offsets along the next two
// axes (u, v), counter-clockwise seen from +axis.
KEYMESH_HD inline int around(int m, int along) {
  constexpr int kAround[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  return kAround[m][along];
}

// The surface nets network's quad of the edge from the padded point whose
// cell (the cube it is the first corner of) is `cell`, along `axis`, from
// label a to label b: the keys of the 4 cells around the edge, as the two
// triangles (C00, C10, C11), (C00, C11, C01), their normal +axis pointing
// from the smaller label to the larger one. cstride: the cells' strides.
template <class K>
KEYMESH_HD void network_quad(Id cell, const Id cstride[3], int axis, bool a_smaller, K out[6]) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  K poly[4];
  for (int m = 0; m < 4; ++m) poly[m] = static_cast<K>(cell - around(m, 0) * cstride[u] - around(m, 1) * cstride[v]);
  if (!a_smaller) {
    const K t = poly[1];
    poly[1] = poly[3], poly[3] = t;
  }
  const K tri[6] = {poly[0], poly[1], poly[2], poly[0], poly[2], poly[3]};
  for (int i = 0; i < 6; ++i) out[i] = tri[i];
}

// How many distinct labels the 8 corners of a cell carry (label(c) is
// corner c's, c in VTK's voxel order); three or more make a junction.
template <class Label>
KEYMESH_HD int distinct_corner_labels(const Label& label) {
  std::uint16_t seen[8];
  int n = 0;
  for (int c = 0; c < 8; ++c) {
    const std::uint16_t l = label(c);
    bool dup = false;
    for (int i = 0; i < n; ++i) dup = dup || seen[i] == l;
    if (!dup) seen[n++] = l;
  }
  return n;
}

// The padded grid's placement of points (LabelVolume::coord): padded
// coordinate i along axis a lies at origin + spacing * (i - 1).
struct Placement {
  double origin[3], spacing[3];
  Id dims[3];  // padded
  KEYMESH_HD double coord(int a, double i) const { return origin[a] + spacing[a] * (i - 1.0); }
  // The point of padded cell g moved by `offset` cell widths from the
  // cell's centre, and the centre (the box smoothing keeps it in); returns
  // the axes along which the cell lies on the padding (bit a).
  KEYMESH_HD std::uint8_t cell_point(const Id g[3], const double offset[3], float* point, float* centre) const {
    std::uint8_t border = 0;
    for (int a = 0; a < 3; ++a) {
      const double c = coord(a, static_cast<double>(g[a]) + 0.5);
      centre[a] = static_cast<float>(c);
      point[a] = static_cast<float>(c + offset[a] * spacing[a]);
      if (g[a] == 0 || g[a] == dims[a] - 2) border |= static_cast<std::uint8_t>(1u << a);
    }
    return border;
  }
};

// One Jacobi step of the smoothing (label_smoothing.cpp) for point p:
// next = x moved by `factor` towards the mean of its neighbours
// neighbours[offsets[p], offsets[p + 1]) (summed in that, increasing, order),
// except along its border axes; `constrained` (surface nets) then clamps it
// to its cell, half a spacing either side of the cell's centre.
struct SmoothStep {
  const Id* offsets;
  const std::uint32_t* neighbours;
  const std::uint8_t* border_axes;
  const float* cell_centre;  // read only when constrained
  double half[3];            // half a spacing per axis
  bool constrained;
  double factor;
  const double* x;
  double* next;
  KEYMESH_HD void operator()(Id p) const {
    const Id b = offsets[p], e = offsets[p + 1];
    // The neighbours' sums, all three axes in one pass over the stencil
    // (each axis still summed in neighbour order).
    double sum[3] = {0, 0, 0};
    for (Id j = b; j < e; ++j) {
      const double* q = x + 3 * static_cast<Id>(neighbours[j]);
      sum[0] += q[0], sum[1] += q[1], sum[2] += q[2];
    }
    for (int a = 0; a < 3; ++a) {
      double v = x[3 * p + a];
      if (e > b && !((border_axes[p] >> a) & 1)) {
        v += factor * (sum[a] / static_cast<double>(e - b) - v);
        if (constrained) {
          const double c = cell_centre[3 * p + a], lo = c - half[a], hi = c + half[a];
          v = v < lo ? lo : (hi < v ? hi : v);  // std::clamp(v, lo, hi)
        }
      }
      next[3 * p + a] = v;
    }
  }
};

// The fold guard of the smoothing (label_fold_guard.cpp has the why): the
// orientation of triangle (p, q, r) against the unit normal n it had
// unsmoothed, ((q - p) x (r - p)) . n; unsmoothed it is twice the area.
KEYMESH_HD inline double orientation(const double* p, const double* q, const double* r, const double* n) {
  const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const double v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
  return (u[1] * v[2] - u[2] * v[1]) * n[0] + (u[2] * v[0] - u[0] * v[2]) * n[1] + (u[0] * v[1] - u[1] * v[0]) * n[2];
}

// Per triangle t, from the unsmoothed points: its unit normal and the least
// orientation the guard keeps, a fraction of twice its area: 0.05 in
// general, 0.5 with a junction corner (three or more labels meet), where
// 0.05 still let triangles of sheets meeting there cross (measured in
// docs/decisions/labels-smoothing-folds.md). A triangle degenerate
// unsmoothed keeps a zero normal and least 1: its corners stay.
struct GuardFrame {
  const float* points;
  const std::uint32_t* corners;  // 3 per triangle
  const std::uint8_t* junction;  // per point
  double* normal;                // 3 per triangle
  double* least;                 // per triangle
  KEYMESH_HD void operator()(Id t) const {
    double c[3][3];
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) c[k][a] = points[3 * static_cast<Id>(corners[3 * t + k]) + a];
    const double u[3] = {c[1][0] - c[0][0], c[1][1] - c[0][1], c[1][2] - c[0][2]};
    const double v[3] = {c[2][0] - c[0][0], c[2][1] - c[0][1], c[2][2] - c[0][2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double twice_area = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int a = 0; a < 3; ++a) normal[3 * t + a] = twice_area > 0 ? n[a] / twice_area : 0.0;
    const bool at_junction = junction[corners[3 * t]] || junction[corners[3 * t + 1]] || junction[corners[3 * t + 2]];
    least[t] = twice_area > 0 ? (at_junction ? 0.5 : 0.05) * twice_area : 1.0;
  }
};

// One guarded move of point p: out = x + f (candidate - x), f the largest of
// 1, 1/2, 1/4, 1/8 for which each of p's triangles keeps its orientation
// at least at its `least` with each other corner at either end of that
// corner's own move (D is linear in each corner, so the four combinations
// bound it whatever fraction the neighbours take), else 0 (p stays). A move
// shortened or refused counts in shortened[p]. `clear` and `clear_point`
// (optional, the host's FoldClearance, label_fold_clearance.hpp): per
// triangle, 1 where every try's test is proven to pass, so it is skipped,
// and per point, 1 where that holds for all its triangles; the same
// decisions. A try fails at the first triangle that fails, and the next try
// starts at that triangle (most failing moves fail at the same one): a try's
// answer does not depend on the order of its tests.
struct GuardStep {
  const std::uint32_t* corners;        // 3 per triangle
  const Id* offsets;                   // per point + 1, into point_corners
  const std::uint32_t* point_corners;  // each point's corners (3 t + k), any order
  const double* normal;
  const double* least;
  const double* x;
  const double* candidate;
  double* out;
  std::uint32_t* shortened;
  const std::uint8_t* clear = nullptr;
  const std::uint8_t* clear_point = nullptr;
  // Whether triangle t, corner p at `at`, keeps its least orientation at the
  // four ends of its two other corners' moves.
  KEYMESH_HD bool keeps_triangle(Id t, Id k, const double at[3]) const {
    const Id q = corners[3 * t + (k + 1) % 3], r = corners[3 * t + (k + 2) % 3];
    const double* qs[2] = {x + 3 * q, candidate + 3 * q};
    const double* rs[2] = {x + 3 * r, candidate + 3 * r};
    for (int i = 0; i < 2; ++i)
      for (int m = 0; m < 2; ++m)
        if (!(orientation(at, qs[i], rs[m], normal + 3 * t) >= least[t])) return false;
    return true;
  }
  // The first of p's corners, from `start` round the list, whose triangle
  // fails with p at `at`; -1 where all keep.
  KEYMESH_HD Id failing(Id p, const double at[3], Id start) const {
    const Id b = offsets[p], e = offsets[p + 1];
    for (Id j = start, n = 0; n < e - b; ++n, j = j + 1 == e ? b : j + 1) {
      const Id t = point_corners[j] / 3;
      if (clear && clear[t]) continue;
      if (!keeps_triangle(t, point_corners[j] % 3, at)) return j;
    }
    return -1;
  }
  KEYMESH_HD void operator()(Id p) const {
    const double* from = x + 3 * p;
    const double* to = candidate + 3 * p;
    double at[3] = {from[0], from[1], from[2]};
    if (to[0] != from[0] || to[1] != from[1] || to[2] != from[2]) {
      bool kept = false;
      int tries = 0;
      Id start = offsets[p];
      for (double f = 1.0; tries < 4 && !kept; f *= 0.5, ++tries) {  // 1, 1/2, 1/4, 1/8: exact
        for (int a = 0; a < 3; ++a) at[a] = from[a] + f * (to[a] - from[a]);
        const Id fail = clear_point && clear_point[p] ? -1 : failing(p, at, start);
        kept = fail < 0;
        if (!kept) {
          start = fail;
          for (int a = 0; a < 3; ++a) at[a] = from[a];
        }
      }
      if (tries > 1 || !kept) ++shortened[p];
    }
    for (int a = 0; a < 3; ++a) out[3 * p + a] = at[a];
  }
};

}  // namespace keymesh::generate::label_kernels
