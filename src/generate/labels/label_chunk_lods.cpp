// A chunk piece one level coarser (see keymesh/generate/labels/labels_multilod.hpp):
// every inner point keyed by the nearest point of the grid of spacing 2^lod
// and one KEY-REDUCE merges them (merge_piece_points, label_coarsen.cpp, the
// coarsening of labels --coarsen: positions averaged in key order, collapsed
// faces dropped, opposite faces on the same points cancelled); the points on
// one face of the chunk's box merge by the nearest grid point on the face
// where the face's cut stays simple, decided from the cut alone
// (label_face_clusters.cpp); points on the box's edge
// lines keep their keys and positions (but for the level's margin, and box
// points closer than a quantization step joined: join_box_points), so
// neighbouring chunks keep the same points on their common face, its border
// lines included, at every level. Then the fold guard
// (label_lod_fold_guard.cpp) splits back the inner clusters of triangles
// that cross, until none is left to split, and lifts the inner corners of
// those still crossing off the chunk planes.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <iterator>
#include <string>
#include <tuple>

#include "keymesh/core/error.hpp"
#include "label_chunks.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

constexpr int kFieldBits = 19;

void join_box_points(MultilodPiece& piece, const MultilodGrid& grid);  // below

// The coarse keys of the inner points of a piece of `chunk` at spacing
// `step` (class 0): what does not depend on the point (each axis's grid
// points per chunk, the chunk's lower plane) computed once per piece.
class CoarseKeys {
 public:
  CoarseKeys(const MultilodGrid& grid, const std::array<std::uint32_t, 3>& chunk, double step)
      : grid_(grid), step_(step) {
    for (int d = 0; d < 3; ++d) {
      const Id per_chunk = static_cast<Id>(std::ceil(static_cast<double>(grid.chunk_shape[d]) / step)) + 1;
      first_[d] = chunk[d] * per_chunk;
      plane_[d] = grid.plane(d, chunk[d]);
    }
  }
  std::uint64_t operator()(const float* p) const {
    std::uint64_t fields = 0;
    for (int d = 0; d < 3; ++d) {
      const Id field = first_[d] + round_half_away((static_cast<double>(p[d]) - plane_[d]) / step_);
      if (field >= (Id{1} << kFieldBits)) too_many_chunks(d);
      fields |= static_cast<std::uint64_t>(field) << (kFieldBits * d);
    }
    return fields;
  }

 private:
  [[noreturn]] void too_many_chunks(int d) const {
    throw LimitError("labels: " + std::to_string(grid_.chunks[d]) + " chunks of " +
                     std::to_string(grid_.chunk_shape[d]) + " samples along an axis are past what a multilod "
                     "output's point keys hold at level spacing " + std::to_string(step_));
  }
  const MultilodGrid& grid_;
  double step_;
  Id first_[3];
  double plane_[3];
};

// The piece of `finer` coarsened by the given keys (one per finer point),
// every coordinate of a point off the chunk planes (all of an inner point's,
// a box point's along the planes it does not lie on) at the level's margin.
// Box points keep their keys, so they keep their positions, save for that
// margin, which moves a coordinate from its value alone: alike in every
// chunk that holds the point.
MultilodPiece coarsened_piece(const MultilodPiece& finer, const MultilodGrid& grid, const std::vector<std::uint64_t>& keys) {
  MultilodPiece out;
  out.segment = finer.segment;
  out.lod = finer.lod + 1;
  out.chunk = finer.chunk;
  merge_piece_points(finer, keys, out);
  const int lod = static_cast<int>(out.lod);
  const ChunkBox box(grid, out.chunk);
  const double margin[3] = {grid.margin(0, lod), grid.margin(1, lod), grid.margin(2, lod)};
  for (std::size_t i = 0; i < out.point_keys.size(); ++i) {
    float* p = out.points.data() + 3 * i;
    const OnBox b = box.at(p);
    for (int a = 0; a < 3; ++a)
      if (!(b.axes >> a & 1)) p[a] = off_chunk_planes(grid, a, p[a], margin[a]);
  }
  join_box_points(out, grid);
  return out;
}

// Box points of one kind (the same planes) whose positions quantize (at the
// piece's level, as the writer does) within one step of each other along
// every axis take the position of the one of least key among them (chains
// included), so the writer merges them into one point
// (io/neuroglancer/coincident_points.hpp). Below a quantization step apart
// they would fold the triangles between them once quantized. Decided from
// the points' kinds and positions alone, which every chunk that holds them
// has alike.
//
// The sets are the connected components of "same kind, within one step":
// sorted by kind and quantized position (an axis the kind's planes leave
// free first), each point meets the few after it within one step along that
// axis. A set's least index (its least key: points run in key order) is
// where union-find's roots end.
void join_box_points(MultilodPiece& piece, const MultilodGrid& grid) {
  const int lod = static_cast<int>(piece.lod);
  const double top = std::ldexp(1.0, grid.vertex_quantization_bits) - 1;
  double size[3], origin[3];
  for (int a = 0; a < 3; ++a) {
    size[a] = std::ldexp(static_cast<double>(grid.chunk_shape[a]), lod);
    origin[a] = grid.grid_origin[a] + static_cast<double>(piece.chunk[a] >> lod) * size[a];
  }
  struct Cell {
    int kind;                       // axes << 3 | upper
    std::array<std::int64_t, 3> q;  // quantized position, the sweep axis first
    std::uint32_t point;
    bool operator<(const Cell& o) const { return std::tie(kind, q, point) < std::tie(o.kind, o.q, o.point); }
  };
  const ChunkBox box(grid, piece.chunk);
  const std::size_t n = piece.point_keys.size();
  std::vector<Cell> cells;
  for (std::uint32_t i = 0; i < n; ++i) {
    const float* p = piece.points.data() + 3 * i;
    const OnBox b = box.at(p);
    if (!b.axes) continue;
    const int sweep = std::countr_one(static_cast<unsigned>(b.axes)) % 3;  // a free axis (any for a corner)
    Cell c{b.axes << 3 | b.upper, {}, i};
    for (int j = 0; j < 3; ++j) {
      const int a = (sweep + j) % 3;
      c.q[static_cast<std::size_t>(j)] = round_half_away((p[a] - origin[a]) / size[a] * top);
    }
    cells.push_back(c);
  }
  std::sort(cells.begin(), cells.end());
  std::vector<std::uint32_t> root(n);
  for (std::uint32_t i = 0; i < n; ++i) root[i] = i;
  auto find = [&](std::uint32_t i) { while (root[i] != i) i = root[i] = root[root[i]]; return i; };
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const Cell& c = cells[i];
    for (std::size_t j = i + 1; j < cells.size() && cells[j].kind == c.kind && cells[j].q[0] <= c.q[0] + 1; ++j) {
      if (std::abs(cells[j].q[1] - c.q[1]) > 1 || std::abs(cells[j].q[2] - c.q[2]) > 1) continue;
      const std::uint32_t u = find(c.point), v = find(cells[j].point);
      root[std::max(u, v)] = std::min(u, v);
    }
  }
  for (const Cell& c : cells) {
    const std::uint32_t r = find(c.point);
    if (r != c.point) std::copy_n(piece.points.begin() + 3 * r, 3, piece.points.begin() + 3 * c.point);
  }
}

}  // namespace

MultilodPiece coarser_piece(const MultilodPiece& finer, const MultilodGrid& grid) {
  const double step = std::ldexp(1.0, static_cast<int>(finer.lod + 1));
  std::vector<std::uint64_t> keys(finer.point_keys.size());
  const ChunkBox box(grid, finer.chunk);
  const CoarseKeys coarse_key(grid, finer.chunk, step);
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const float* p = finer.points.data() + 3 * i;
    keys[i] = box.at(p).axes ? finer.point_keys[i] : coarse_key(p);
  }
  cluster_face_points(finer, grid, keys);
  // Each round splits at least one cluster for good (a split point is never
  // split again) or lifts at least one more point, so this ends.
  std::vector<std::uint64_t> lifted;
  for (;;) {
    MultilodPiece out = coarsened_piece(finer, grid, keys);
    lift_off_planes(out, grid, lifted);
    const std::vector<char> crossing = crossing_triangles(out, grid);
    if (split_clusters(keys, clusters_to_split(out, crossing))) continue;
    const std::vector<std::uint64_t> more = points_to_lift(out, grid, crossing);
    std::vector<std::uint64_t> all;
    std::set_union(lifted.begin(), lifted.end(), more.begin(), more.end(), std::back_inserter(all));
    if (all.size() == lifted.size()) return out;
    lifted = std::move(all);
  }
}

}  // namespace keymesh::generate::detail
