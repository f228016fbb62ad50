#pragma once
// Points that quantization puts on one integer point, merged: the format
// stores only the quantized positions, so two distinct points that round to
// one are one point to every reader, and a triangle on both would be a
// zero-area triangle (the project writes none). Merging them is a simplicial
// map: triangles left with two corners on one point collapse (dropped), and
// triangles left on the same three points in opposite orientations cancel
// (the first |net| of the winning orientation stay, in triangle order), so a
// closed 2-cycle stays one and no triangle folds onto another.
//
// Decided from the quantized positions alone: two nodes sharing a face hold
// the same points on it (same quantized values), so they merge them alike,
// and a point off the chunk planes keeps two quantization steps from them,
// so it never merges with a face point.
#include <cstdint>
#include <vector>

#include "draco_fragment.hpp"

namespace keymesh::io::neuroglancer {

// In place: each set of points with equal positions becomes its first
// point; triangles collapsed or cancelled are removed; points no triangle
// uses are removed (the others keep their order). A mesh without such
// points is left as it is. Returns, per point of the result, 1 where a
// triangle at the point had a merged corner (empty when nothing merged):
// the points whose boundary edges the merge can have changed.
std::vector<std::uint8_t> merge_coincident_points(QuantizedMesh& mesh);

}  // namespace keymesh::io::neuroglancer
