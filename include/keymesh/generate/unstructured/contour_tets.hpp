#pragma once
// Marching tetrahedra on an unstructured tetrahedral grid, welded by history
// (paper, Section 4.2 and Table 2's tetrahedral rows).
//
// The key of a triangle corner is the input edge it lies on, named by its two
// point ids, smaller first: (min << b) | max, with b the bits of the point
// count (plus iso_index << 2b for several isovalues). Tets that list a shared
// edge in opposite orders still produce the same key, which is what welds a
// conforming tet mesh into a closed surface; KEY-REDUCE's sort plan groups
// the corners (the key range, N^2, is too wide to address directly).
//
// Guarantees (as for the voxel contour, contour.hpp):
//  - inside means value >= iso; NaN samples are outside; one point per cut
//    edge, positions interpolated from the smaller id towards the larger, so
//    an edge gives the same point whichever tet names it;
//  - triangles point from inside (>= iso) to outside, whatever the handedness
//    of each input tet (each cut tet's orientation is read off its volume);
//  - every point field is carried, interpolated along the edge; normals by
//    averaging incident face normals (ContourNormals::Gradient is refused);
//  - output bit-identical for any thread count; ContourWeld::VertexWeld gives
//    the same mesh up to point order.
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::generate {

// Throws InputError when the grid has cells other than tetrahedra, no such
// point field, or invalid isovalues; LimitError past 2^32 - 1 output points
// or corners, or when the edge keys need more than 64 bits.
// History (options.history, docs/HISTORY.md): point field "history_t", the
// float t from the edge's smaller point id a towards b for which
//   x[c] = float(double(P[a][c]) + double(t) * (double(P[b][c]) - double(P[a][c])))
// gives all three written coordinates back where such a float exists near
// the crossing's t; point_keys, when given, receives every point's edge key
// (history_key): iso_index << 2b | a << b | b_id, b the bits of the
// largest point id (at least 1). Not with coarsening (InputError).
// Runs on the CPU: options.backend must be Backend::Cpu
// (keymesh/backend/contour.hpp chooses the GPU).
SurfaceMesh contour(const UnstructuredGrid& tets, const ContourOptions& options, ContourStats* stats = nullptr,
                    std::vector<std::uint64_t>* point_keys = nullptr);

// contour()'s input checks alone (the same InputError); returns the point
// field to contour. For the device path (contour_tets_device.hpp), which
// runs on any device: options.backend is not read.
const Field& check_tet_contour_input(const UnstructuredGrid& tets, const ContourOptions& options);

}  // namespace keymesh::generate
