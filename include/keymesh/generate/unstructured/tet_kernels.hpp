#pragma once
// The per-element arithmetic of marching tetrahedra (contour_tets.hpp) and of
// the tet generators, shared by their CPU paths (src/generate/unstructured/)
// and their device paths (contour_tets_device.hpp): plain values and
// KEYMESH_HD functions, so every device computes the same bits.
#include <cmath>
#include <cstdint>

#include "keymesh/core/device.hpp"
#include "keymesh/core/types.hpp"
#include "keymesh/mesh/keys.hpp"

namespace keymesh::generate {

// Signed volume of tet (a, b, c, d): det(b - a, c - a, d - a) / 6.
KEYMESH_HD inline double tet_volume(const float* a, const float* b, const float* c, const float* d) {
  const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
  const double v[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
  const double w[3] = {double(d[0]) - a[0], double(d[1]) - a[1], double(d[2]) - a[2]};
  return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])) /
         6.0;
}

// The five-tet splits of a voxel (tetrahedralize5): tet[parity][t] the four
// corners (bit order: corner c at (c & 1, (c >> 1) & 1, (c >> 2) & 1)) of tet t
// of the split used where i + j + k has that parity, positively oriented.
struct FiveTetSplits {
  std::uint8_t tet[2][5][4];
};

// Built once (src/generate/unstructured/tetrahedralize.cpp).
const FiveTetSplits& five_tet_splits();

// The position of grid point p of a voxel grid (x fastest).
struct GridPoints {
  Id nx, nxy;
  double origin[3], spacing[3];
  KEYMESH_HD void position(Id p, float* xyz) const {
    const Id k = p / nxy, j = (p - k * nxy) / nx, i = p - k * nxy - j * nx;
    const Id ijk[3] = {i, j, k};
    for (int a = 0; a < 3; ++a) xyz[a] = static_cast<float>(origin[a] + spacing[a] * static_cast<double>(ijk[a]));
  }
};

// The 24 tets of a hexahedron (tetrahedralize24) from its corner ids (bit
// order), its face-centre ids and its centre id: per face and face edge, the
// edge, the face centre and the cell centre, oriented by their volume in P.
KEYMESH_HD inline void hex_tets24(const std::uint64_t corner[8], const std::uint64_t face[6], std::uint64_t centre,
                                  const float* P, std::uint64_t tets[24][4]) {
  constexpr int kCycle[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  int k = 0;
  for (int f = 0; f < 6; ++f)
    for (int e = 0; e < 4; ++e) {
      std::uint64_t* v = tets[k++];
      v[0] = corner[kCycle[f][e]], v[1] = corner[kCycle[f][(e + 1) % 4]], v[2] = face[f], v[3] = centre;
      if (tet_volume(P + 3 * v[0], P + 3 * v[1], P + 3 * v[2], P + 3 * v[3]) < 0) {
        const std::uint64_t t = v[0];
        v[0] = v[1], v[1] = t;
      }
    }
}

// Marching tetrahedra cases: bit v of the case is set when corner v is
// inside; triangles[m] triangles (0, 1 or 2) whose corners lie on tet edges
// edges[m][3 t + c] (cells::kTetEdges), wound on the positively oriented
// reference tet so that normals point from inside to outside.
struct TetTable {
  std::uint8_t triangles[16];
  std::uint8_t edges[16][6];
};

// Built once (src/generate/unstructured/contour_tets.cpp).
const TetTable& tet_table();

// Where the point of an edge key lies: its end points a < b and the
// parameter t from a to b.
struct TetEdgePoint {
  std::uint64_t a, b;
  double t;
};

struct TetEdgePoints {
  EdgeKeys ek;
  const double* isovalues;  // indexed by the key's level
  const float* P;           // grid points
  const float* S;           // the contoured samples

  KEYMESH_HD TetEdgePoint locate(std::uint64_t key) const {
    TetEdgePoint e{};
    const auto ab = ek.decode(key);
    e.a = ab.first, e.b = ab.second;
    const double iso = isovalues[ek.level(key)];
    const double t = (iso - double(S[e.a])) / (double(S[e.b]) - double(S[e.a]));
    // A NaN end sample (outside by definition) has no crossing: midway.
    e.t = std::isfinite(t) ? (t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t)) : 0.5;
    return e;
  }
  KEYMESH_HD void position(std::uint64_t key, float* xyz) const {
    const TetEdgePoint e = locate(key);
    for (int a = 0; a < 3; ++a) {
      const double pa = P[3 * e.a + a], pb = P[3 * e.b + a];
      xyz[a] = static_cast<float>(pa + e.t * (pb - pa));
    }
  }
  // A point field's tuple at the point of `key` (k components, `values` the
  // grid's), interpolated along the edge; where that is not finite, the
  // finite end's value, and for the contoured field (`contoured`) the isovalue.
  KEYMESH_HD void tuple(std::uint64_t key, const float* values, int k, bool contoured, float* out) const {
    const TetEdgePoint e = locate(key);
    for (int c = 0; c < k; ++c) {
      const double va = values[e.a * k + c], vb = values[e.b * k + c];
      const double v = va + e.t * (vb - va);
      const float value = static_cast<float>(std::isfinite(v) ? v : (std::isfinite(va) ? va : vb));
      out[c] = contoured && !std::isfinite(value) ? static_cast<float>(isovalues[ek.level(key)]) : value;
    }
  }
};

}  // namespace keymesh::generate
