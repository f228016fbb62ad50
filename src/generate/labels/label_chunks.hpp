#pragma once
// Internal to the multilod label surfaces (labels_multilod.hpp): one
// segment's surface cut into lod-0 chunk pieces (label_chunk_clip.cpp) and
// each piece coarsened per level (label_chunk_lods.cpp).
#include <array>
#include <cstdint>
#include <vector>

#include "keymesh/generate/labels/labels_multilod.hpp"

namespace keymesh::generate::detail {

// One segment's welded, smoothed surface: global point keys (class 0 of
// labels_multilod.hpp), stored model coordinates.
struct SegmentSurface {
  std::uint64_t segment = 0;
  std::vector<std::uint64_t> keys;
  std::vector<float> points;
  std::vector<std::uint32_t> triangles;
};

// Moves every coordinate that lies exactly on a chunk plane one float step
// down (towards -inf): a point then lies on a chunk plane only where a
// triangle is cut there.
void move_off_chunk_planes(SegmentSurface& surface, const MultilodGrid& grid);
// Whether v (along `axis`) lies exactly on a chunk plane.
bool on_chunk_plane(const MultilodGrid& grid, int axis, float v);

// The segment's triangles grouped by the lod-0 chunks their bounding boxes
// meet: chunk ids (x + chunks_x * (y + chunks_y * z)), increasing, and for
// each its triangles (increasing).
struct ChunkTriangles {
  std::vector<Id> chunk;
  std::vector<Id> offsets;              // chunk.size() + 1
  std::vector<std::uint32_t> triangles;
};
ChunkTriangles triangles_by_chunk(const SegmentSurface& surface, const MultilodGrid& grid);

// The level-0 piece of `chunk` from the given triangles: each clipped to the
// chunk's box (points made on its planes keyed and placed canonically),
// welded by key. Empty when nothing of the triangles lies in the box.
LabelPiece clip_to_chunk(const SegmentSurface& surface, const MultilodGrid& grid, const std::array<Id, 3>& chunk,
                         const std::uint32_t* triangles, Id count);

// The piece one level coarser (lod + 1), from `finer`.
LabelPiece coarser_piece(const LabelPiece& finer, const MultilodGrid& grid);

}  // namespace keymesh::generate::detail
