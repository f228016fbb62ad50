#pragma once
// One octree node's mesh from the chunk pieces inside it: the pieces welded
// by their global point keys (KEY-REDUCE: each piece's increasing keys merged, no
// coordinates compared), each point quantized over the node's box as the
// format specifies:
//   x = round((p - node_origin) / node_size * (2^bits - 1)),
//   node_origin = grid_origin + P * chunk_shape * 2^lod, node_size = chunk_shape * 2^lod.
//
// A point outside the node's box by more than float rounding is an internal
// error (std::logic_error): the meshing broke the contract, and clamping it
// would hide a misplaced point. Points that round to one integer point stay
// apart here; the writer merges them next (coincident_points.hpp). A
// triangle with two corners of one key is an internal error (the meshing
// hands only proper triangles).
#include <array>
#include <vector>

#include "draco_fragment.hpp"
#include "keymesh/io/neuroglancer.hpp"
#include "octree_nodes.hpp"

namespace keymesh::io::neuroglancer {

struct NodeBox {
  std::array<double, 3> origin{};
  std::array<double, 3> size{};
};

NodeBox node_box(const MultilodLayout& layout, std::uint32_t lod, const NodePosition& node);

// The welded, quantized mesh of `pieces` (one segment, one lod, chunks inside
// the node), in the order given; points in increasing key order.
QuantizedMesh node_fragment(const std::vector<const ChunkPiece*>& pieces, const NodeBox& box, int quantization_bits);

}  // namespace keymesh::io::neuroglancer
