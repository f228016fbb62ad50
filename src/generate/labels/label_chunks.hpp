#pragma once
// Internal to the multilod label surfaces (labels_multilod.hpp): one
// segment's surface cut into lod-0 chunk pieces (label_chunk_clip.cpp) and
// each piece coarsened per level (label_chunk_lods.cpp) under a fold guard
// (label_lod_fold_guard.cpp).
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

// The piece one level coarser (lod + 1), from `finer`: its inner points
// coarsened, its face points merged where their face's cut allows
// (label_face_clusters.cpp), its edge-line points kept
// (label_chunk_lods.cpp), and the inner clusters of crossing triangles split
// back until none is left to split, then the inner corners of those still
// crossing lifted off the chunk planes (label_lod_fold_guard.cpp).
MultilodPiece coarser_piece(const MultilodPiece& finer, const MultilodGrid& grid);

// The finer piece's points merged by `coarse` (a key per point) as
// coarsen_label_surface merges a surface's (label_coarsen.cpp): the points of
// one key averaged in increasing index, collapsed triangles dropped,
// opposite triangles on the same points cancelled, unused points dropped.
// Writes out's points, point_keys (the coarse keys kept, increasing) and
// triangles.
//
// Inputs with fewer than `serial_below` points (or faces) group serially (the
// points by a hash of their keys, first_seen_keys.hpp, and a sort of the
// distinct keys; the faces by a counting sort): a chunk piece (hundreds of points,
// coarsened every level and fold-guard round) would spend more on the
// parallel KEY-REDUCE plans' set-up (radix digits, bitmaps, per-chunk
// counts) than on its points; larger ones use those plans. Both give the
// same groups, so the same output (coarsen_label_surface uses the default).
constexpr Id kCoarsenSerialBelow = Id{1} << 15;
void merge_piece_points(const MultilodPiece& finer, const std::vector<std::uint64_t>& coarse, MultilodPiece& out,
                        Id serial_below = kCoarsenSerialBelow);

// The coarse keys of the finer piece's face points (on one plane of the
// chunk's box) into `keys` (one per finer point, the finer keys there):
// merged by the nearest grid point of spacing 2^(finer.lod + 1) on the face
// where the face's cut stays simple, decided from the face's cut alone
// (label_face_clusters.cpp); edge-line points keep theirs.
void cluster_face_points(const MultilodPiece& finer, const MultilodGrid& grid, std::vector<std::uint64_t>& keys);

// The coarsening's fold guard (label_lod_fold_guard.cpp). Per triangle of
// `coarse`, 1 where, at the positions the writer quantizes its points to, it
// crosses another triangle of the piece or is a line (three distinct
// collinear points). Computed once per round and handed to both remedies
// below, which judge the same piece.
std::vector<char> crossing_triangles(const MultilodPiece& coarse, const MultilodGrid& grid);
// The keys of the inner coarse points (class 0, not yet split) at a corner
// of a crossing triangle (`crossing`: crossing_triangles(coarse, ...));
// increasing.
std::vector<std::uint64_t> clusters_to_split(const MultilodPiece& coarse, const std::vector<char>& crossing);
// The finer points whose coarse key is one of `clusters` (increasing) get
// keys of their own: class 0, bit 60 set, their rank in the cluster (in
// index order, at most 63: the 64th on stay together) in bits 54-59 and the
// cluster's three grid fields in 18 bits each (a cluster whose fields do not
// fit, past 2^18 / 2 samples along an axis, stays whole). False when no
// point changed.
bool split_clusters(std::vector<std::uint64_t>& coarse_keys, const std::vector<std::uint64_t>& clusters);

// The guard's second remedy, once no cluster is left to split: the inner
// points (off the chunk's box) at a corner of a triangle of `coarse` that
// still crosses another or is a line (`crossing`: crossing_triangles(coarse,
// grid)), increasing keys. Where a merged face point moved along its face, the
// finest inner points near the face (a patch of the surface lying within a
// margin of the plane, which surface nets clamps onto sample planes) can
// fold over it, and its neighbour, which holds the same face point, sees
// nothing of it.
std::vector<std::uint64_t> points_to_lift(const MultilodPiece& coarse, const MultilodGrid& grid,
                                          const std::vector<char>& crossing);
// The points of `coarse` whose keys are in `lifted` (increasing) keep
// min(2^lod / 8, chunk_shape / 4) samples from every plane of the chunk's
// box (moved inside along each axis where closer): the piece's own inner
// points, which no neighbour sees, so faces still agree.
void lift_off_planes(MultilodPiece& coarse, const MultilodGrid& grid, const std::vector<std::uint64_t>& lifted);

// Which chunk planes of the piece's chunk a point lies on: bit a of `axes`
// set when on one along axis a, bit a of `upper` when that is the chunk's
// upper plane.
struct OnBox {
  int axes = 0, upper = 0;
  int count() const { return (axes & 1) + (axes >> 1 & 1) + (axes >> 2 & 1); }
};
// std::llround(v) for |v| < 2^52 (every quantity rounded here), inline where
// GCC calls libm for llround and round: v - trunc(v) is exact.
inline std::int64_t round_half_away(double v) {
  const auto t = static_cast<std::int64_t>(v);
  const double fraction = v - static_cast<double>(t);
  return t + (fraction >= 0.5 ? 1 : 0) - (fraction <= -0.5 ? 1 : 0);
}

// The planes of a chunk's box, computed once for the many points of a piece.
struct ChunkBox {
  std::array<double, 3> lo{}, hi{};
  ChunkBox(const MultilodGrid& grid, const std::array<std::uint32_t, 3>& chunk) {
    for (int a = 0; a < 3; ++a) lo[a] = grid.plane(a, chunk[a]), hi[a] = grid.plane(a, chunk[a] + 1);
  }
  OnBox at(const float* p) const {
    OnBox b;
    for (int a = 0; a < 3; ++a) {
      const bool low = p[a] == lo[a], high = p[a] == hi[a];
      b.axes |= (low || high) ? 1 << a : 0;
      b.upper |= high ? 1 << a : 0;
    }
    return b;
  }
};
inline OnBox on_box(const float* p, const MultilodGrid& grid, const std::array<std::uint32_t, 3>& chunk) {
  return ChunkBox(grid, chunk).at(p);
}

}  // namespace keymesh::generate::detail
