#pragma once
// Face points that the coincident-point merge left without a boundary edge,
// moved off the node's face. Two nodes sharing a face hold the same points
// on it, and a point there stays used in a node because it ends a boundary
// edge of the node's piece (the directed edges its triangles leave
// unpaired): the cut curve both nodes share. When quantization puts two face
// points on one integer point, the merge can make that point's boundary
// edges in the face cancel (a tiny loop of the cut closes up), the same way
// in both nodes (the same integers); its triangles may then all collapse in
// one node and not in the other, so one node would list the point on the
// face and the other not. A point that ends no boundary edge lying in a
// face plane is moved off that plane into the node by two quantization
// steps (the margin every point not made on a plane keeps): the boundary is
// unchanged, so the piece stays a closed 2-cycle with its neighbours, and in
// both nodes the point is off the face (moved, or dropped with its last
// triangle). Decided from integer positions and the node's own triangles.
#include <cstdint>
#include <vector>

#include "draco_fragment.hpp"

namespace keymesh::io::neuroglancer {

// In place, for the points `candidates` marks (merge_coincident_points'
// result: the others' boundary edges are the generator's, which keeps every
// used face point on one); `bits`: the quantization (node faces at 0 and
// 2^bits - 1). Returns how many points were moved.
int settle_face_points(QuantizedMesh& mesh, int bits, const std::vector<std::uint8_t>& candidates);

}  // namespace keymesh::io::neuroglancer
