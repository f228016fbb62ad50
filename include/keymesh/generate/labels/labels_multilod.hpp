#pragma once
// Multi-resolution label surfaces cut into chunks (issue 37): for every
// segment (selected label) and every lod-0 chunk, the piece of the segment's
// surface inside the chunk at each level of detail. The io layer writes them
// as Neuroglancer's "neuroglancer_multilod_draco" (io/neuroglancer.hpp); the
// pieces here are its ChunkPiece, field for field.
//
// Coordinates ("stored model" space): grid index space, sample i at i. The
// surfaces of labels.hpp reach half a spacing past the grid (the padding),
// so the chunk grid starts one sample before it: lod-0 chunk (i, j, k) is
// the box  -1 + [i, j, k] * chunk_shape ... + chunk_shape, and
// chunks = ceil((dims + 1) / chunk_shape) per axis cover [-1, dims].
//
// Level 0: each segment's own closed surface (LabelOptions::per_label),
// welded and smoothed as contour_labels makes it, then clipped at the chunk
// planes. A coordinate of a surface point that falls exactly on a chunk
// plane (surface nets clamps points onto sample planes) is moved one float
// step down first, so a point lies on a plane only where a triangle crosses
// it. A point made by clipping is computed from the segment's points in key
// order (an edge's two ends, or a triangle's three points for a point on a
// chunk edge line), so every chunk that has it computes the same bits; so
// two neighbouring chunks have the same points on their common face.
//
// Level k >= 1: the chunk's level k-1 piece, its inner points (those off
// the chunk's box) merged by one KEY-REDUCE (label_coarsen.cpp: positions
// averaged in key order, collapsed faces dropped, opposite faces on the same
// points cancelled) over keys = the nearest point of the grid of spacing 2^k
// (relative to the chunk's corner). Its points on one face of the box merge
// in the same KEY-REDUCE by the nearest grid point on the face, where the
// face's cut (its points and the boundary edges in the face plane, which
// both chunks of the face hold alike) stays simple at the writer's quantized
// positions, each such cluster one run of one strand; others, those within
// half a grid step of the face's border, and the points on the box's edge
// lines keep their keys and positions (label_face_clusters.cpp). A
// coordinate off the planes is kept at the level's margin; box points on
// the same planes that quantize within one step of each other at the level
// take the position of the least key among them, for the writer to merge,
// decided from their positions alone. So two neighbouring chunks have the
// same points on their common face, its border lines included, at every
// level, with no data from each other. A fold guard
// (label_lod_fold_guard.cpp) then splits back into their finer points the
// inner clusters at a corner of a triangle that crosses another (at the
// positions the writer quantizes to), until none is left to split, and
// lifts the inner corners of triangles still crossing off the chunk planes
// (docs/decisions/labels-lod-fold-guard.md).
//
// Point keys (unique within a segment and level, equal in every chunk that
// has the point; bits 61-63 a class):
//   level 0, class 0: the generator's point. Surface nets (per label):
//     ((z << 36 | y << 18 | x) << 4) | s with (x, y, z) the padded grid cell,
//     s the loop (0-3) or 4 + 2 * axis + arc for a face point; discrete MC:
//     ((z << 36 | y << 18 | x) << 2) | axis, the padded grid edge.
//   level 0, classes 1-3: made on a chunk plane normal to axis class-1;
//     4-6: on a chunk edge line along axis class-4. Then
//     (cz << 43 | cy << 25 | cx << 7) | rank: the unit cell of the padded
//     grid holding the point (floor), and its rank among that cell's points
//     of the class, by the points they are made from.
//   level k >= 1: a merged face cluster takes the key of its least point,
//     other points on the chunk's box keep theirs; an
//     inner point has class 0 and three 19-bit fields (z << 38 | y << 19 | x):
//     chunk * (R + 1) + round((coordinate - chunk corner) / 2^k) with
//     R = ceil(chunk_shape / 2^k); one the fold guard split out of its
//     cluster has bit 60 set, its rank in the cluster in bits 54-59 and the
//     cluster's fields in 18 bits each (z << 36 | y << 18 | x).
// So volumes are limited to 2^18 - 2 samples along an axis (LimitError).
//
// Chunk tasks: multilod_chunk_pieces meshes the chunk's box grown by
// multilod_halo samples, enough that every point the chunk's triangles use
// is smoothed exactly as in the whole volume (a smoothing step moves a point
// from its neighbours, at most one cell away; the arithmetic runs over
// neighbours in key order, which any sub-volume keeps), so its pieces equal
// multilod_pieces' for that chunk bit for bit.
//
// Refused (InputError): coarsen (the levels coarsen), negative labels
// (segment ids are unsigned), a chunk shape below 2 or a level count below 1,
// chunks outside the grid.
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "keymesh/generate/labels/labels.hpp"
#include "keymesh/mesh/image_grid.hpp"

namespace keymesh::generate {

struct MultilodOptions {
  LabelOptions labels;  // method, selection, background, smoothing (per_label implied)
  std::array<Id, 3> chunk_shape{32, 32, 32};
  int lods = 3;
  // The writer's quantization (io::neuroglancer::MultilodLayout): a point
  // not on a chunk plane keeps two quantization steps of its level's node
  // away from every chunk plane, so that it never rounds onto a node's face.
  int vertex_quantization_bits = 16;
};

// The chunk grid of a volume of `dims` samples.
struct MultilodGrid {
  std::array<Id, 3> chunk_shape{32, 32, 32};
  std::array<Id, 3> chunks{1, 1, 1};
  std::array<double, 3> grid_origin{-1, -1, -1};  // stored model coordinates of chunk (0, 0, 0)
  int lods = 1;
  int vertex_quantization_bits = 16;
  double plane(int axis, Id index) const { return grid_origin[axis] + static_cast<double>(index * chunk_shape[axis]); }
  // The distance a point off the chunk planes keeps from them at `lod`: two
  // quantization steps of a node (chunk_shape * 2^lod).
  double margin(int axis, int lod) const {
    return std::ldexp(2.0 * static_cast<double>(chunk_shape[axis]), lod) / (std::ldexp(1.0, vertex_quantization_bits) - 1);
  }
};

// One lod-0 chunk's share of one segment's surface at one level of detail
// (io::neuroglancer::ChunkPiece).
struct MultilodPiece {
  std::uint64_t segment = 0;
  std::uint32_t lod = 0;
  std::array<std::uint32_t, 3> chunk{0, 0, 0};
  std::vector<std::uint64_t> point_keys;  // increasing
  std::vector<float> points;              // x,y,z per point, inside the chunk's box
  std::vector<std::uint32_t> triangles;   // 3 per triangle, outward normals
};

MultilodGrid multilod_grid(const std::array<Id, 3>& dims, const MultilodOptions& options);

// Samples a chunk task reads past its chunk's box along each axis.
Id multilod_halo(const MultilodOptions& options);

// Every chunk's pieces, meshing the whole volume once; sorted by (segment,
// lod, chunk z, y, x). Pieces with no points are left out.
std::vector<MultilodPiece> multilod_pieces(const ImageGrid& grid, const MultilodOptions& options);

// One chunk's pieces (a chunk task), from the chunk's box and its halo of
// `grid` only: equal to the pieces of multilod_pieces for that chunk.
std::vector<MultilodPiece> multilod_chunk_pieces(const ImageGrid& grid, const MultilodOptions& options,
                                              const std::array<Id, 3>& chunk);

// The samples a chunk task reads: [lo, lo + dims) of the whole volume (the
// chunk's box grown by multilod_halo, inside the volume). InputError for a
// chunk outside the grid of chunks.
struct MultilodBox {
  std::array<Id, 3> lo{}, dims{};
};
MultilodBox multilod_chunk_box(const std::array<Id, 3>& whole_dims, const MultilodOptions& options,
                               const std::array<Id, 3>& chunk);
// multilod_chunk_pieces from the box's samples alone (box_samples: box.dims,
// sample i at whole-volume index box.lo + i), so a task can read just those
// planes of a large volume.
std::vector<MultilodPiece> multilod_box_pieces(const ImageGrid& box_samples, const std::array<Id, 3>& whole_dims,
                                            const MultilodBox& box, const MultilodOptions& options,
                                            const std::array<Id, 3>& chunk);

// The chunks whose pieces can change when the samples inside `changed`
// chunks change: those within the halo's reach, in increasing (z, y, x).
std::vector<std::array<Id, 3>> multilod_affected_chunks(const MultilodGrid& grid, const MultilodOptions& options,
                                                        const std::vector<std::array<Id, 3>>& changed);

}  // namespace keymesh::generate
