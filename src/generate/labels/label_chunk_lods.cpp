// A chunk piece one level coarser (see keymesh/generate/labels/labels_multilod.hpp):
// every point keyed by the nearest point of the grid of spacing 2^lod, kept
// on the chunk face or box edge it lies on, and one KEY-REDUCE merges them
// (coarsen_label_surface: positions averaged in key order, collapsed faces
// dropped, opposite faces on the same points cancelled). Then the boundary
// is led past the edge-line points it does not cross
// (reroute_line_boundaries), and the box points the chunks sharing them
// would not all keep move into the chunk (settle_box_points), so
// neighbouring chunks keep the same points on their common face, its border
// lines included.
#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>

#include "keymesh/core/error.hpp"
#include "label_chunks.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

constexpr int kClassShift = 61;
constexpr int kMovedBit = 60;      // a box point moved into its chunk
constexpr int kSideShift = 57;     // then bit 57 + a: the chunk lies above the plane along a
constexpr int kFieldBits = 19;

// The coarse key of point p of a piece of `chunk` at spacing `step`.
std::uint64_t coarse_key(const float* p, const MultilodGrid& grid, const std::array<std::uint32_t, 3>& chunk,
                         double step) {
  const OnBox b = on_box(p, grid, chunk);
  std::uint64_t fields = 0;
  int free_axis = 0, plane_axis = 0;
  for (int d = 0; d < 3; ++d) {
    const Id c = chunk[d];
    const Id per_chunk = static_cast<Id>(std::ceil(static_cast<double>(grid.chunk_shape[d]) / step)) + 1;
    Id field = 0;
    if (b.axes >> d & 1) {
      plane_axis = d;
      field = (b.upper >> d & 1 ? c + 1 : c) * per_chunk;
    } else {
      free_axis = d;
      field = c * per_chunk + std::llround((static_cast<double>(p[d]) - grid.plane(d, c)) / step);
    }
    if (field >= (Id{1} << kFieldBits))
      throw LimitError("labels: " + std::to_string(grid.chunks[d]) + " chunks of " +
                       std::to_string(grid.chunk_shape[d]) + " samples along an axis are past what a multilod "
                       "output's point keys hold at level spacing " + std::to_string(step));
    fields |= static_cast<std::uint64_t>(field) << (kFieldBits * d);
  }
  const int n = b.count();
  const int cls = n == 0 ? 0 : n == 1 ? 1 + plane_axis : n == 2 ? 4 + free_axis : 7;
  return static_cast<std::uint64_t>(cls) << kClassShift | fields;
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
  MultilodPiece out;
  out.segment = finer.segment;
  out.lod = finer.lod + 1;
  out.chunk = finer.chunk;
  const double step = std::ldexp(1.0, static_cast<int>(out.lod));
  const std::size_t points = finer.point_keys.size();
  LabelSurface s;
  s.mesh.points.assign(finer.points.begin(), finer.points.end());
  s.mesh.connectivity.assign(finer.triangles.begin(), finer.triangles.end());
  s.pair.assign(finer.triangles.size() / 3, 0);
  s.keys = finer.point_keys;  // so that coarsening leaves the coarse keys of the points it keeps
  s.coarse.resize(points);
  for (std::size_t i = 0; i < points; ++i) s.coarse[i] = coarse_key(finer.points.data() + 3 * i, grid, finer.chunk, step);
  LabelStats stats;
  coarsen_label_surface(s, stats);
  out.point_keys = std::move(s.keys);
  out.points.assign(s.mesh.points.begin(), s.mesh.points.end());
  out.triangles.assign(s.mesh.connectivity.begin(), s.mesh.connectivity.end());
  reroute_line_boundaries(out, grid);
  settle_box_points(out, grid);
  return out;
}

void settle_box_points(MultilodPiece& piece, const MultilodGrid& grid) {
  const std::size_t n = piece.point_keys.size();
  std::vector<OnBox> box(n);
  for (std::size_t i = 0; i < n; ++i) box[i] = on_box(piece.points.data() + 3 * i, grid, piece.chunk);
  const std::vector<char> held = held_by_boundary(piece, box);
  const int lod = static_cast<int>(piece.lod);
  const double step = std::ldexp(1.0, lod);
  bool moved = false;
  for (std::size_t i = 0; i < n; ++i) {
    float* p = piece.points.data() + 3 * i;
    for (int a = 0; a < 3; ++a) {
      const double margin = grid.margin(a, lod);
      if (box[i].count() == 2 && !(box[i].axes >> a & 1)) {
        // A point on an edge line: at its grid point along the line, from its
        // key alone (so the same in the four chunks around the line, whatever
        // the rounding of an average); one the boundary leaves then also
        // moves off both its planes, below.
        const Id per_chunk = static_cast<Id>(std::ceil(static_cast<double>(grid.chunk_shape[a]) / step)) + 1;
        const Id field = static_cast<Id>(piece.point_keys[i] >> (kFieldBits * a) & ((std::uint64_t{1} << kFieldBits) - 1));
        const double lo = grid.plane(a, piece.chunk[a]), hi = grid.plane(a, piece.chunk[a] + 1);
        const double at = lo + static_cast<double>(field - static_cast<Id>(piece.chunk[a]) * per_chunk) * step;
        p[a] = static_cast<float>(std::clamp(at, lo + margin, hi - margin));
      } else if (!(box[i].axes >> a & 1)) {
        p[a] = off_chunk_planes(grid, a, p[a], margin);
      } else if (!held[i]) {  // into the chunk, a key of its own
        const bool upper = box[i].upper >> a & 1;
        p[a] = static_cast<float>(grid.plane(a, piece.chunk[a] + (upper ? 1 : 0)) + (upper ? -margin : margin));
        piece.point_keys[i] |= std::uint64_t{1} << kMovedBit | std::uint64_t{upper ? 0u : 1u} << (kSideShift + a);
        moved = true;
      }
    }
  }
  if (!moved) return;
  // Keys increasing again: renumber the points in key order.
  std::vector<std::uint32_t> order(n), rank(n);
  for (std::uint32_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return piece.point_keys[a] < piece.point_keys[b]; });
  MultilodPiece sorted = piece;
  for (std::size_t r = 0; r < n; ++r) {
    rank[order[r]] = static_cast<std::uint32_t>(r);
    sorted.point_keys[r] = piece.point_keys[order[r]];
    std::copy_n(piece.points.begin() + 3 * order[r], 3, sorted.points.begin() + 3 * r);
  }
  for (std::uint32_t& c : sorted.triangles) c = rank[c];
  piece = std::move(sorted);
}

}  // namespace keymesh::generate::detail
