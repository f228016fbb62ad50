#pragma once
// Triangles whose three distinct corners lie on one line (zero area; the
// project writes none), flipped away: with b strictly between a and c, the
// triangle (a, b, c) and its neighbour (a, c, d) across the long side become
// (a, b, d) and (b, c, d). The two tile the neighbour exactly (b lies on its
// side a-c), so no point moves, no triangle crosses another that did not,
// and the directed edges left unpaired are the same (a closed 2-cycle stays
// one). Decided on the quantized integer positions (exact), in triangle
// order; points and their positions are untouched, so faces shared with
// other nodes keep their points.
//
// Left as they are: a line whose long side has no single neighbour in the
// node (it lies on the node's face, or the side is non-manifold), or whose
// neighbour is on the line too after every other flip.
#include "draco_fragment.hpp"

namespace keymesh::io::neuroglancer {

// In place; returns how many triangles were flipped away.
int flip_collinear_triangles(QuantizedMesh& mesh);

}  // namespace keymesh::io::neuroglancer
