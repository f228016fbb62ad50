// A chunk piece one level coarser (see keymesh/generate/labels/labels_multilod.hpp):
// every point keyed by the nearest point of the grid of spacing 2^lod, kept
// on the chunk face or box edge it lies on, and one KEY-REDUCE merges them
// (coarsen_label_surface: positions averaged in key order, collapsed faces
// dropped, opposite faces on the same points cancelled). Then the box points
// the chunks sharing them would not all keep move into the chunk
// (settle_box_points), so neighbouring chunks keep the same points on their
// common face.
#include <algorithm>
#include <cmath>
#include <map>
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

// Which chunk planes a point lies on: bit a set when on one along axis a,
// `upper` bit a when that is the chunk's upper plane.
struct OnBox {
  int axes = 0, upper = 0;
  int count() const { return (axes & 1) + (axes >> 1 & 1) + (axes >> 2 & 1); }
};

OnBox on_box(const float* p, const MultilodGrid& grid, const std::array<std::uint32_t, 3>& chunk) {
  OnBox b;
  for (int a = 0; a < 3; ++a) {
    const bool low = p[a] == grid.plane(a, chunk[a]), high = p[a] == grid.plane(a, chunk[a] + 1);
    b.axes |= (low || high) ? 1 << a : 0;
    b.upper |= high ? 1 << a : 0;
  }
  return b;
}

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

// The box points the piece's boundary holds: the ends of its boundary
// edges (the directed edges between box points its triangles leave
// unpaired) on a face of the box. A face shared by two chunks has opposite
// boundaries in them (the chain map of coarsening keeps level 0's, where
// both chunks' triangles end on the same cut), so both hold the same points
// of its inside; a box point off every boundary edge has its edges paired
// within the chunk, and moving it keeps every segment a closed 2-cycle.
std::vector<char> held_by_boundary(const MultilodPiece& piece, const std::vector<OnBox>& box) {
  // Net directed edges between box points (smaller index first, +1 along).
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> net;
  for (std::size_t t = 0; t < piece.triangles.size(); t += 3)
    for (int m = 0; m < 3; ++m) {
      const std::uint32_t a = piece.triangles[t + m], b = piece.triangles[t + (m + 1) % 3];
      if (box[a].axes == 0 || box[b].axes == 0) continue;
      net[{std::min(a, b), std::max(a, b)}] += a < b ? 1 : -1;
    }
  std::vector<char> held(box.size(), 0);
  for (const auto& [edge, n] : net) {
    if (n == 0) continue;
    held[edge.first] = held[edge.second] = 1;
  }
  return held;
}

}  // namespace

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
        // A point on an edge line: at its grid point along the line (from its
        // key alone), as the four chunks around the line may merge different
        // points there.
        const Id per_chunk = static_cast<Id>(std::ceil(static_cast<double>(grid.chunk_shape[a]) / step)) + 1;
        const Id field = static_cast<Id>(piece.point_keys[i] >> (kFieldBits * a) & ((std::uint64_t{1} << kFieldBits) - 1));
        const double lo = grid.plane(a, piece.chunk[a]), hi = grid.plane(a, piece.chunk[a] + 1);
        const double at = lo + static_cast<double>(field - static_cast<Id>(piece.chunk[a]) * per_chunk) * step;
        p[a] = static_cast<float>(std::clamp(at, lo + margin, hi - margin));
      } else if (!(box[i].axes >> a & 1)) {
        p[a] = off_chunk_planes(grid, a, p[a], margin);
      } else if (!held[i] && box[i].count() == 1) {  // into the chunk, a key of its own
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
