// A chunk piece one level coarser (see keymesh/generate/labels/labels_multilod.hpp):
// every inner point keyed by the nearest point of the grid of spacing 2^lod
// and one KEY-REDUCE merges them (coarsen_label_surface: positions averaged
// in key order, collapsed faces dropped, opposite faces on the same points
// cancelled); the points on the chunk's box keep their keys and positions,
// so neighbouring chunks keep the same points on their common face, its
// border lines included, at every level. Then the fold guard
// (label_lod_fold_guard.cpp) splits back the inner clusters of triangles
// that cross, until none is left to split.
#include <algorithm>
#include <cmath>
#include <string>

#include "keymesh/core/error.hpp"
#include "label_chunks.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

constexpr int kFieldBits = 19;

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
  return out;
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
  // Each round splits at least one cluster for good (a split point is never
  // split again), so this ends.
  for (;;) {
    MultilodPiece out = coarsened_piece(finer, grid, keys);
    if (!split_clusters(keys, clusters_to_split(out, grid))) return out;
  }
}

}  // namespace keymesh::generate::detail
