#pragma once
// One segment's manifest and fragment data from all its chunk pieces: the
// nodes octree_nodes.hpp lists, each node's pieces welded and quantized
// (node_fragment.hpp) and Draco-encoded, lod 0 first, each lod in Z-curve
// order. The bytes depend only on the set of pieces, not their order.
#include <cstdint>
#include <string>
#include <vector>

#include "keymesh/io/neuroglancer.hpp"

namespace keymesh::io::neuroglancer {

struct SegmentFiles {
  std::uint64_t segment = 0;
  std::string manifest;
  std::string data;  // the fragments, concatenated in manifest order
};

// `pieces`: the segment's pieces (checked by check_piece); pieces without
// triangles are ignored. Empty manifest when no piece has a triangle (the
// segment has no mesh and no files).
SegmentFiles encode_segment(const MultilodLayout& layout, std::uint64_t segment, std::vector<const ChunkPiece*> pieces);

}  // namespace keymesh::io::neuroglancer
