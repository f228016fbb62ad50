#pragma once
// What the writer checks of its input before writing anything: a layout the
// format can hold, and pieces that keep the contract of neuroglancer.hpp
// (one per segment, lod and chunk; inside the grid of chunks; consistent
// array sizes; corners naming points of the piece). InputError otherwise.
#include <array>
#include <cstdint>
#include <vector>

#include "keymesh/io/neuroglancer.hpp"

namespace keymesh::io::neuroglancer {

void check_layout(const MultilodLayout& layout);

void check_piece(const MultilodLayout& layout, const ChunkPiece& piece);

// The pieces grouped by segment (increasing), each group in input order;
// throws on two pieces of one segment, lod and chunk.
std::vector<std::pair<std::uint64_t, std::vector<const ChunkPiece*>>> pieces_by_segment(const std::vector<ChunkPiece>& pieces);

}  // namespace keymesh::io::neuroglancer
