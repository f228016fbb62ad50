// A chunk piece one level coarser (see keymesh/generate/labels/labels_multilod.hpp):
// every point keyed by the nearest point of the grid of spacing 2^lod, kept
// on the chunk face or box edge it lies on, and one KEY-REDUCE merges them
// (coarsen_label_surface: positions averaged in key order, collapsed faces
// dropped, opposite faces on the same points cancelled). The chunk's face
// points are kept even when no face is left on them, so the chunks that
// share a face keep the same points on it.
#include <cmath>
#include <string>

#include "keymesh/core/error.hpp"
#include "label_chunks.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

constexpr int kClassShift = 61;
constexpr int kFieldBits = 20;

// The coarse key of point p of a piece of `chunk` at spacing `step`, and
// whether it lies on the chunk's box (a face or an edge line).
std::uint64_t coarse_key(const float* p, const MultilodGrid& grid, const std::array<std::uint32_t, 3>& chunk,
                         double step, bool& on_box) {
  int forced = 0, free_axis = 0, plane_axis = 0;
  std::uint64_t fields = 0;
  for (int d = 0; d < 3; ++d) {
    const Id c = chunk[d];
    const double lo = grid.plane(d, c), hi = grid.plane(d, c + 1);
    const Id per_chunk = static_cast<Id>(std::ceil(static_cast<double>(grid.chunk_shape[d]) / step)) + 1;
    Id field = 0;
    if (p[d] == lo || p[d] == hi) {
      ++forced;
      plane_axis = d;
      field = (p[d] == lo ? c : c + 1) * per_chunk;
    } else {
      free_axis = d;
      field = c * per_chunk + std::llround((static_cast<double>(p[d]) - lo) / step);
    }
    if (field >= (Id{1} << kFieldBits))
      throw LimitError("labels: " + std::to_string(grid.chunks[d]) + " chunks of " +
                       std::to_string(grid.chunk_shape[d]) + " samples along an axis are past what a multilod "
                       "output's point keys hold at level spacing " + std::to_string(step));
    fields |= static_cast<std::uint64_t>(field) << (kFieldBits * d);
  }
  on_box = forced > 0;
  const int cls = forced == 0 ? 0 : forced == 1 ? 1 + plane_axis : forced == 2 ? 4 + free_axis : 7;
  return static_cast<std::uint64_t>(cls) << kClassShift | fields;
}

}  // namespace

LabelPiece coarser_piece(const LabelPiece& finer, const MultilodGrid& grid) {
  LabelPiece out;
  out.segment = finer.segment;
  out.lod = finer.lod + 1;
  out.chunk = finer.chunk;
  const double step = std::ldexp(1.0, static_cast<int>(out.lod));
  const std::size_t points = finer.point_keys.size();
  LabelSurface s;
  s.mesh.points.assign(finer.points.begin(), finer.points.end());
  s.mesh.connectivity.assign(finer.triangles.begin(), finer.triangles.end());
  s.pair.assign(finer.triangles.size() / 3, 0);
  s.coarse.resize(points);
  s.keep.resize(points);
  for (std::size_t i = 0; i < points; ++i) {
    bool on_box = false;
    s.coarse[i] = coarse_key(finer.points.data() + 3 * i, grid, finer.chunk, step, on_box);
    s.keep[i] = on_box ? 1 : 0;
  }
  LabelStats stats;
  coarsen_label_surface(s, stats);
  out.point_keys = std::move(s.keys);
  out.points.assign(s.mesh.points.begin(), s.mesh.points.end());
  out.triangles.assign(s.mesh.connectivity.begin(), s.mesh.connectivity.end());
  return out;
}

}  // namespace keymesh::generate::detail
