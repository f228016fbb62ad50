#pragma once
// A segment's manifest (meshes.md, "Multi-resolution mesh manifest file
// format"), all little endian:
//   chunk_shape 3 x f32, grid_origin 3 x f32, num_lods u32,
//   lod_scales num_lods x f32 (2^lod: a lod-k node's mesh resolves 2^k
//     samples; the info's lod_scale_multiplier is 1),
//   vertex_offsets num_lods x 3 x f32 (zeros),
//   num_fragments_per_lod num_lods x u32,
//   per lod: fragment_positions as a C-order [3, n] u32 array (every x, then
//     every y, then every z), fragment_offsets n x u32 (each fragment's size
//     in bytes; its data starts where the previous one's ends).
#include <cstdint>
#include <string>
#include <vector>

#include "keymesh/io/neuroglancer.hpp"
#include "octree_nodes.hpp"

namespace keymesh::io::neuroglancer {

struct LodFragments {
  std::vector<NodePosition> positions;  // Z-curve order
  std::vector<std::uint32_t> sizes;     // bytes of each fragment, 0 for an empty listed node
};

std::string manifest_bytes(const MultilodLayout& layout, const std::vector<LodFragments>& lods);

}  // namespace keymesh::io::neuroglancer
