#pragma once
// The per-element arithmetic of uniform subdivision (subdivide.hpp), shared by
// the CPU path (src/generate/unstructured/subdivide.cpp) and the device path
// (subdivide_device.hpp): plain KEYMESH_HD functions, so every device computes
// the same bits.
#include <cmath>
#include <cstdint>

#include "keymesh/core/device.hpp"
#include "keymesh/generate/unstructured/tet_kernels.hpp"

namespace keymesh::generate::subdivision {

struct V3 {
  double x, y, z;
};
KEYMESH_HD inline V3 load(const float* p) { return {p[0], p[1], p[2]}; }
KEYMESH_HD inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
KEYMESH_HD inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
KEYMESH_HD inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
KEYMESH_HD inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
KEYMESH_HD inline V3 unit(V3 a) {
  const double l = std::sqrt(dot(a, a));
  return l > 0 ? (1.0 / l) * a : V3{0, 0, 0};
}
KEYMESH_HD inline void store(V3 v, float* out) {
  out[0] = float(v.x), out[1] = float(v.y), out[2] = float(v.z);
}

// The new point of edge (pa, pb): its midpoint, or with normals na, nb (the
// Bezier scheme) the midpoint of the edge's cubic of a PN triangle (Vlachos
// et al. 2001), and then, when nrm is given, the PN quadratic normal there.
KEYMESH_HD inline void edge_point(const float* pa_f, const float* pb_f, const float* na_f, const float* nb_f,
                                  float* xyz, float* nrm) {
  const V3 pa = load(pa_f), pb = load(pb_f);
  V3 p = 0.5 * (pa + pb);
  if (na_f) {
    const V3 na = load(na_f), nb = load(nb_f);
    // Control points b1 = (2a + b - w_ab na) / 3, b2 = (2b + a - w_ba nb) / 3;
    // the cubic's midpoint is (a + 3 b1 + 3 b2 + b) / 8.
    const V3 b1 = (1.0 / 3.0) * (2.0 * pa + pb - dot(pb - pa, na) * na);
    const V3 b2 = (1.0 / 3.0) * (2.0 * pb + pa - dot(pa - pb, nb) * nb);
    p = 0.125 * (pa + 3.0 * b1 + 3.0 * b2 + pb);
    if (nrm) {
      const V3 d = pb - pa;
      const double dd = dot(d, d);
      const double v = dd > 0 ? 2.0 * dot(d, na + nb) / dd : 0.0;
      const V3 n110 = unit(na + nb - v * d);
      store(unit(na + nb + n110), nrm);
    }
  }
  store(p, xyz);
}

// A point field's tuple at a new point: the mean of the edge's two tuples
// (in float), renormalised in double for "Normals".
KEYMESH_HD inline void midpoint_tuple(const float* a, const float* b, int components, bool renormalize, float* out) {
  for (int c = 0; c < components; ++c) out[c] = 0.5f * (a[c] + b[c]);
  if (renormalize) store(unit(load(out)), out);
}

// The eight children of a tet (1 -> 8): v holds its corners 0-3, then the
// midpoints of edges 01 02 03 12 13 23, as point ids into P (the output
// points). The four corner tets, then the inner octahedron cut along its
// shortest diagonal (the first among equals); every child positively
// oriented (two corners swapped where its volume is negative).
KEYMESH_HD inline void tet_children(const std::uint64_t v[10], const float* P, std::uint64_t out[8][4]) {
  enum { A, B, C, D, AB, AC, AD, BC, BD, CD };
  // The inner octahedron's three diagonals: (AB, CD), (AC, BD), (AD, BC).
  const int diag[3][2] = {{AB, CD}, {AC, BD}, {AD, BC}};
  int best = 0;
  double best_len = 1.7976931348623157e308;  // DBL_MAX
  for (int d = 0; d < 3; ++d) {
    const V3 x = load(P + 3 * v[diag[d][0]]) - load(P + 3 * v[diag[d][1]]);
    if (dot(x, x) < best_len) best_len = dot(x, x), best = d;
  }
  // The four other octahedron vertices, in cyclic order around the diagonal.
  const int ring[3][4] = {{AC, BC, BD, AD}, {AB, BC, CD, AD}, {AB, BD, CD, AC}};
  int child[8][4] = {{A, AB, AC, AD}, {AB, B, BC, BD}, {AC, BC, C, CD}, {AD, BD, CD, D}};
  for (int k = 0; k < 4; ++k) {
    child[4 + k][0] = diag[best][0];
    child[4 + k][1] = diag[best][1];
    child[4 + k][2] = ring[best][k];
    child[4 + k][3] = ring[best][(k + 1) % 4];
  }
  for (int c = 0; c < 8; ++c) {
    std::uint64_t* w = out[c];
    for (int k = 0; k < 4; ++k) w[k] = v[child[c][k]];
    if (tet_volume(P + 3 * w[0], P + 3 * w[1], P + 3 * w[2], P + 3 * w[3]) < 0) {
      const std::uint64_t t = w[2];
      w[2] = w[3], w[3] = t;
    }
  }
}

}  // namespace keymesh::generate::subdivision
