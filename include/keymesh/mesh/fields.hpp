#pragma once
// Field helpers every generator shares: new points get their tuples from the
// input points that made them (the reduce half of KEY-REDUCE for fields),
// new cells repeat their parent cell's tuple. One arithmetic per helper, so a
// field's bytes do not depend on which generator wrote it.
#include <cstdint>
#include <vector>

#include "keymesh/core/device.hpp"
#include "keymesh/core/types.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh {

// Output arrays come at their final size (parallel::resize_fresh: huge pages
// asked for, first touch shared by the threads), unwritten (Array), and are
// written in place: the caller writes every new tuple.

// Point fields for `points` new points, named and shaped like `like`.
std::vector<Field> new_point_fields(const std::vector<Field>& like, Id points);

// The output point fields of a generator that keeps the input points as
// its first ones: each input field's tuples, then room for the new points
// up to `total` points.
std::vector<Field> extend_point_fields(const std::vector<Field>& in, Id total);

// The same for the coordinates (3 per point): `out` sized for `total`
// points, the input's first.
void extend_points(const Array<float>& in, Id total, Array<float>& out);

// out[i]'s tuple at `point` = the mean, summed in double, of in[i]'s tuples
// at ids[0 .. n) (a face or cell centre).
// (Inline, as mean_position below: called once per new point, from hot
// parallel loops in other layers; out of line they cost tetrahedralize 24
// about 15 % at 96^3, measured.)
// out = the mean, summed in double, of the k-component tuples ids[0 .. n)
// of `values`: the one arithmetic of face and cell centres (KEYMESH_HD: the
// device paths compute the same bits).
KEYMESH_HD inline void mean_tuple(const float* values, int k, const std::uint64_t* ids, int n, float* out) {
  for (int c = 0; c < k; ++c) {
    double s = 0;
    for (int j = 0; j < n; ++j) s += values[ids[j] * k + c];
    out[c] = static_cast<float>(s / n);
  }
}

inline void average_point_fields(const std::vector<Field>& in, std::vector<Field>& out, Id point,
                                 const std::uint64_t* ids, int n) {
  for (std::size_t i = 0; i < in.size(); ++i) {
    const int k = in[i].components;
    mean_tuple(in[i].values.data(), k, ids, n, &out[i].values[point * k]);
  }
}

// xyz = the mean, summed in double, of points ids[0 .. n) of P (a face or
// cell centre).
inline void mean_position(const float* P, const std::uint64_t* ids, int n, float* xyz) { mean_tuple(P, 3, ids, n, xyz); }

// f_out's tuple at `point` = 0.5f * (tuple a + tuple b) in float (an edge's
// midpoint, as subdivision places it).
inline void midpoint_tuple(const Field& f, Field& f_out, Id point, std::uint64_t a, std::uint64_t b) {
  const int k = f.components;
  for (int c = 0; c < k; ++c) f_out.values[point * k + c] = 0.5f * (f.values[a * k + c] + f.values[b * k + c]);
}

// Every cell's tuple repeated for its `children` cells, which follow one
// another in the output (cell c's children are c * children + 0 ..
// children - 1).
std::vector<Field> repeat_cell_fields(const std::vector<Field>& in, Id cells, int children);

}  // namespace keymesh
