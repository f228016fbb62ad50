#pragma once
// The label generators' per-element work shared by their CPU paths
// (labels_surface_nets.cpp, label_smoothing.cpp) and the device path
// (labels_device.hpp), so that both give the same bits: the surface nets
// network's quad of an edge, a cell's point, the junction test, and one
// Jacobi step of the smoothing.
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

}  // namespace keymesh::generate::label_kernels
