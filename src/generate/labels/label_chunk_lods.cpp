// A chunk piece one level coarser (see keymesh/generate/labels/labels_multilod.hpp):
// every inner point keyed by the nearest point of the grid of spacing 2^lod
// and one KEY-REDUCE merges them (coarsen_label_surface: positions averaged
// in key order, collapsed faces dropped, opposite faces on the same points
// cancelled); the points on one face of the chunk's box merge by the
// nearest grid point on the face where the face's cut stays simple, decided
// from the cut alone (label_face_clusters.cpp); points on the box's edge
// lines keep their keys and positions (but for the level's margin, and box
// points closer than a quantization step joined: join_box_points), so
// neighbouring chunks keep the same points on their common face, its border
// lines included, at every level. Then the fold guard
// (label_lod_fold_guard.cpp) splits back the inner clusters of triangles
// that cross, until none is left to split, and lifts the inner corners of
// those still crossing off the chunk planes.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <string>

#include "keymesh/core/error.hpp"
#include "label_chunks.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

constexpr int kFieldBits = 19;

void join_box_points(MultilodPiece& piece, const MultilodGrid& grid);  // below

// The coarse key of inner point p of a piece of `chunk` at spacing `step`
// (class 0).
std::uint64_t coarse_key(const float* p, const MultilodGrid& grid, const std::array<std::uint32_t, 3>& chunk,
                         double step) {
  std::uint64_t fields = 0;
  for (int d = 0; d < 3; ++d) {
    const Id c = chunk[d];
    const Id per_chunk = static_cast<Id>(std::ceil(static_cast<double>(grid.chunk_shape[d]) / step)) + 1;
    const Id field = c * per_chunk + std::llround((static_cast<double>(p[d]) - grid.plane(d, c)) / step);
    if (field >= (Id{1} << kFieldBits))
      throw LimitError("labels: " + std::to_string(grid.chunks[d]) + " chunks of " +
                       std::to_string(grid.chunk_shape[d]) + " samples along an axis are past what a multilod "
                       "output's point keys hold at level spacing " + std::to_string(step));
    fields |= static_cast<std::uint64_t>(field) << (kFieldBits * d);
  }
  return fields;
}

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
  LabelSurface s;
  s.mesh.points.assign(finer.points.begin(), finer.points.end());
  s.mesh.connectivity.assign(finer.triangles.begin(), finer.triangles.end());
  s.pair.assign(finer.triangles.size() / 3, 0);
  s.keys = finer.point_keys;  // so that coarsening leaves the coarse keys of the points it keeps
  s.coarse = keys;
  LabelStats stats;
  coarsen_label_surface(s, stats);
  out.point_keys = std::move(s.keys);
  out.points.assign(s.mesh.points.begin(), s.mesh.points.end());
  out.triangles.assign(s.mesh.connectivity.begin(), s.mesh.connectivity.end());
  const int lod = static_cast<int>(out.lod);
  for (std::size_t i = 0; i < out.point_keys.size(); ++i) {
    float* p = out.points.data() + 3 * i;
    const OnBox b = on_box(p, grid, out.chunk);
    for (int a = 0; a < 3; ++a)
      if (!(b.axes >> a & 1)) p[a] = off_chunk_planes(grid, a, p[a], grid.margin(a, lod));
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
void join_box_points(MultilodPiece& piece, const MultilodGrid& grid) {
  const int lod = static_cast<int>(piece.lod);
  const double top = std::ldexp(1.0, grid.vertex_quantization_bits) - 1;
  using Cell = std::array<std::int64_t, 5>;  // kind (axes, upper), quantized x, y, z
  std::map<Cell, std::uint32_t> at;
  const std::size_t n = piece.point_keys.size();
  std::vector<std::uint32_t> root(n);
  for (std::uint32_t i = 0; i < n; ++i) root[i] = i;
  auto find = [&](std::uint32_t i) { while (root[i] != i) i = root[i] = root[root[i]]; return i; };
  for (std::uint32_t i = 0; i < n; ++i) {  // in key order: a root is its set's least key
    const float* p = piece.points.data() + 3 * i;
    const OnBox b = on_box(p, grid, piece.chunk);
    if (!b.axes) continue;
    Cell c{b.axes, b.upper, 0, 0, 0};
    for (int a = 0; a < 3; ++a) {
      const double size = std::ldexp(static_cast<double>(grid.chunk_shape[a]), lod);
      const double origin = grid.grid_origin[a] + static_cast<double>(piece.chunk[a] >> lod) * size;
      c[2 + a] = static_cast<std::int64_t>(std::llround((p[a] - origin) / size * top));
    }
    for (int d = 0; d < 27; ++d) {
      const Cell nb{c[0], c[1], c[2] + d % 3 - 1, c[3] + d / 3 % 3 - 1, c[4] + d / 9 - 1};
      const auto f = at.find(nb);
      if (f == at.end()) continue;
      const std::uint32_t u = find(f->second), v = find(i);
      root[std::max(u, v)] = std::min(u, v);
    }
    at.emplace(c, i);
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t r = find(i);
    if (r != i) std::copy_n(piece.points.begin() + 3 * r, 3, piece.points.begin() + 3 * i);
  }
}

}  // namespace

OnBox on_box(const float* p, const MultilodGrid& grid, const std::array<std::uint32_t, 3>& chunk) {
  OnBox b;
  for (int a = 0; a < 3; ++a) {
    const bool low = p[a] == grid.plane(a, chunk[a]), high = p[a] == grid.plane(a, chunk[a] + 1);
    b.axes |= (low || high) ? 1 << a : 0;
    b.upper |= high ? 1 << a : 0;
  }
  return b;
}

MultilodPiece coarser_piece(const MultilodPiece& finer, const MultilodGrid& grid) {
  const double step = std::ldexp(1.0, static_cast<int>(finer.lod + 1));
  std::vector<std::uint64_t> keys(finer.point_keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const float* p = finer.points.data() + 3 * i;
    keys[i] = on_box(p, grid, finer.chunk).axes ? finer.point_keys[i] : coarse_key(p, grid, finer.chunk, step);
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
