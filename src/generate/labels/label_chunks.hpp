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

// Which chunk planes of the piece's chunk a point lies on: bit a of `axes`
// set when on one along axis a, bit a of `upper` when that is the chunk's
// upper plane.
struct OnBox {
  int axes = 0, upper = 0;
  int count() const { return (axes & 1) + (axes >> 1 & 1) + (axes >> 2 & 1); }
};
OnBox on_box(const float* p, const MultilodGrid& grid, const std::array<std::uint32_t, 3>& chunk);

// The box points the piece's boundary holds: the ends of its boundary
// edges (the directed edges between box points its triangles leave
// unpaired). A face shared by two chunks has opposite boundaries in them
// (the chain map of coarsening keeps level 0's, where both chunks' triangles
// end on the same cut), so both hold the same points of it; a box point off
// every boundary edge has its edges paired within the chunk, and moving it
// keeps every segment a closed 2-cycle.
std::vector<char> held_by_boundary(const MultilodPiece& piece, const std::vector<OnBox>& box);

// A coarse piece's boundary (the directed edges between box points its
// triangles leave unpaired) led past the points on the chunk's edge lines
// that it does not cross: on each face at such a point, the boundary edges
// in (x -> K) and out (K -> y), which balance, are paired in key order and
// each pair closed by a triangle (y, K, x), so the face's boundary runs
// x -> y instead. Decided from the face's boundary alone, so the two chunks
// of a face lead it alike; a line point is then held by the boundary in all
// four chunks around its line (a crossing) or in none.
void reroute_line_boundaries(MultilodPiece& piece, const MultilodGrid& grid);

// A coarse piece's points on the chunk's box kept there only where the
// piece's boundary (the directed edges its triangles leave unpaired) holds
// them: they end a boundary edge on a face of the box. Any other box point
// (its triangles close up around it: a tube across the face shrunk to a
// point) moves into the chunk by the level's margin, with a key of its own.
// A point on an edge line that stays sits at its key's grid point along the
// line (from its key alone); one the boundary leaves moves into the chunk
// along both planes. Then every other coordinate keeps the margin from the
// chunk planes.
void settle_box_points(MultilodPiece& piece, const MultilodGrid& grid);

}  // namespace keymesh::generate::detail
