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

// v (along `axis`) at least `margin` from every chunk plane: one closer
// moves to that distance on its side (one on a plane: below it). A point
// then lies on a chunk plane only where it was made there, and never rounds
// onto one in the writer's quantization.
float off_chunk_planes(const MultilodGrid& grid, int axis, float v, double margin);
// Every coordinate of the surface's points off the chunk planes (level 0's margin).
void move_off_chunk_planes(SegmentSurface& surface, const MultilodGrid& grid);

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
MultilodPiece clip_to_chunk(const SegmentSurface& surface, const MultilodGrid& grid, const std::array<Id, 3>& chunk,
                         const std::uint32_t* triangles, Id count);

// The piece one level coarser (lod + 1), from `finer`.
MultilodPiece coarser_piece(const MultilodPiece& finer, const MultilodGrid& grid);

// A coarse piece's points on the chunk's box kept there only where the
// piece's boundary (the directed edges its triangles leave unpaired) holds
// them: they end a boundary edge on a face of the box. Any other box point
// (its triangles close up around it: a tube across the face shrunk to a
// point) moves into the chunk by the level's margin, with a key of its own.
// A point on an edge line sits at its key's grid point along the line (the
// four chunks around the line may merge different points into it, so no
// average). Then every other coordinate keeps the margin from the chunk
// planes.
void settle_box_points(MultilodPiece& piece, const MultilodGrid& grid);

}  // namespace keymesh::generate::detail
