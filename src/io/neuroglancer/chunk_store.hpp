#pragma once
// The chunk tasks' pieces, kept under DIR/chunks/ until the final step:
//   DIR/chunks/layout.json     the layout every task and the final step must share;
//   DIR/chunks/I_J_K.pieces    one chunk's pieces, in a private binary container:
//     "KMNGPCS1" magic, u32 version, u32 chunk I J K, u64 piece count,
//     u64 payload bytes, u32 CRC-32 of the payload; then per piece
//     u64 segment, u32 lod, u64 points, u64 triangles, u64 keys[points],
//     f32 xyz[3 * points], u32 corners[3 * triangles]; all little endian.
// A truncated, corrupted or foreign file is refused by name (InputError),
// never read as pieces.
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "keymesh/io/neuroglancer.hpp"

namespace keymesh::io::neuroglancer {

std::string chunk_pieces_path(const std::string& dir, const std::array<std::uint32_t, 3>& chunk);
std::string layout_record_path(const std::string& dir);

// The layout record's text (fixed key order).
std::string layout_record(const MultilodLayout& layout);

// Throws InputError unless DIR/chunks/layout.json records `layout`, naming
// the first field that differs (or saying that no chunk task has run).
void check_layout_record(const std::string& dir, const MultilodLayout& layout);

std::string encode_chunk_pieces(const std::array<std::uint32_t, 3>& chunk, const std::vector<const ChunkPiece*>& pieces);

// Which pieces to decode: keep(segment, triangles); the others are skipped
// (their bytes still checked by the CRC).
using PieceFilter = std::function<bool(std::uint64_t segment, std::uint64_t triangles)>;

// The pieces of the chunk file at `path` that `keep` accepts (all when keep is empty).
std::vector<ChunkPiece> decode_chunk_pieces(const std::string& path, const std::array<std::uint32_t, 3>& chunk,
                                            const PieceFilter& keep = {});

}  // namespace keymesh::io::neuroglancer
