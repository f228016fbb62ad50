// A segment's surface cut into lod-0 chunk pieces (see
// keymesh/generate/labels/labels_multilod.hpp): every triangle that meets a
// chunk's box is clipped to it (Sutherland-Hodgman over the box's six
// planes); a point the clipping makes is named by what it is made from (an
// edge of the triangle and a plane, or the triangle and two planes: a point
// on a chunk edge line) and placed from those points in key order, so every
// chunk that makes it gets the same bits. Sides are decided on these
// positions, and no point lies on a plane it was not made on (the surface's
// points were moved off the planes, and a made coordinate landing on one
// moves one float step down), so the chunks on either side of a plane cut a
// triangle at the same points.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "label_chunks.hpp"

namespace keymesh::generate::detail {

namespace {

constexpr int kClassShift = 61;
constexpr int kCellBits = 18;
constexpr int kRankBits = 7;

// A point of a clipped polygon: what it is made from, and where it lies.
struct ClipPoint {
  int kind = 0;                           // 0 a surface point, 1 an edge cut by a plane, 2 a triangle by two planes
  int axis[2] = {0, 0};                   // the planes' axes (kind 2: increasing)
  double plane[2] = {0, 0};               // their coordinates
  std::uint64_t from[3] = {0, 0, 0};      // keys of the surface points it is made from, increasing
  float p[3] = {0, 0, 0};
  std::uint32_t index = 0;                // kind 0: the surface point's index
  auto name() const { return std::tie(kind, axis[0], axis[1], plane[0], plane[1], from[0], from[1], from[2]); }
};

// Where a polygon side runs: along an edge of the triangle (its ends), or
// along a plane it was cut at.
struct Side {
  bool on_plane = false;
  int axis = 0;
  double plane = 0;
  std::uint32_t a = 0, b = 0;
};

struct Clipper {
  const SegmentSurface& s;
  const MultilodGrid& grid;
  std::uint32_t tri[3];  // the triangle's points, in key order

  const float* at(std::uint32_t i) const { return s.points.data() + 3 * static_cast<std::size_t>(i); }

  const double* lo;  // the chunk's box
  const double* hi;
  int stage = 0;  // the axis being clipped

  // A made coordinate along `axis`: the margin inside the box's slab along
  // the axes clipped before (the point lies on a side between points inside
  // it, and every chunk that makes the point has that slab), off the chunk
  // planes along the others (decided later, by its value alone).
  float settle(int axis, double v) const {
    const float f = static_cast<float>(v);
    const double margin = grid.margin(axis, 0);
    if (axis < stage) {
      const float low = static_cast<float>(lo[axis] + margin), high = static_cast<float>(hi[axis] - margin);
      return f < low ? low : f > high ? high : f;
    }
    return off_chunk_planes(grid, axis, f, margin);
  }

  ClipPoint surface_point(std::uint32_t i) const {
    ClipPoint c;
    c.from[0] = s.keys[i];
    c.index = i;
    std::copy_n(at(i), 3, c.p);
    return c;
  }

  // Edge (a, b) cut by the plane `axis` = x.
  ClipPoint edge_cut(std::uint32_t a, std::uint32_t b, int axis, double x) const {
    if (s.keys[b] < s.keys[a]) std::swap(a, b);
    ClipPoint c;
    c.kind = 1;
    c.axis[0] = c.axis[1] = axis;
    c.plane[0] = c.plane[1] = x;
    c.from[0] = s.keys[a], c.from[1] = s.keys[b];
    const float *pa = at(a), *pb = at(b);
    const double t = (x - pa[axis]) / (static_cast<double>(pb[axis]) - pa[axis]);
    for (int d = 0; d < 3; ++d)
      c.p[d] = d == axis ? static_cast<float>(x) : settle(d, pa[d] + t * (static_cast<double>(pb[d]) - pa[d]));
    return c;
  }

  // The triangle cut by the planes axis0 = x0 and axis1 = x1 (a point on a
  // chunk edge line).
  ClipPoint line_point(int axis0, double x0, int axis1, double x1) const {
    if (axis1 < axis0) std::swap(axis0, axis1), std::swap(x0, x1);
    ClipPoint c;
    c.kind = 2;
    c.axis[0] = axis0, c.axis[1] = axis1;
    c.plane[0] = x0, c.plane[1] = x1;
    for (int m = 0; m < 3; ++m) c.from[m] = s.keys[tri[m]];
    const float *a = at(tri[0]), *b = at(tri[1]), *q = at(tri[2]);
    double e1[3], e2[3];
    for (int d = 0; d < 3; ++d) e1[d] = static_cast<double>(b[d]) - a[d], e2[d] = static_cast<double>(q[d]) - a[d];
    const double r0 = x0 - a[axis0], r1 = x1 - a[axis1];
    const double det = e1[axis0] * e2[axis1] - e2[axis0] * e1[axis1];
    const int f = 3 - axis0 - axis1;
    double v = (static_cast<double>(a[f]) + b[f] + q[f]) / 3.0;  // a triangle along the line: its centroid's
    if (det != 0.0) {
      const double u = (r0 * e2[axis1] - e2[axis0] * r1) / det, w = (e1[axis0] * r1 - r0 * e1[axis1]) / det;
      v = a[f] + u * e1[f] + w * e2[f];
    }
    c.p[axis0] = static_cast<float>(x0), c.p[axis1] = static_cast<float>(x1), c.p[f] = settle(f, v);
    return c;
  }

  // Keeps the part of the polygon on one side of the plane axis = x (below:
  // coordinates <= x), in place; out and out_sides: scratch (kept between
  // calls, so a clip allocates nothing once they have grown).
  void clip(std::vector<ClipPoint>& poly, std::vector<Side>& sides, std::vector<ClipPoint>& out,
            std::vector<Side>& out_sides, int axis, double x, bool below) {
    stage = axis;
    auto inside = [&](const ClipPoint& c) { return below ? c.p[axis] <= x : c.p[axis] >= x; };
    const std::size_t n = poly.size();
    // A plane the polygon lies inside (most of the six: a clipped triangle
    // mostly crosses one) leaves it as it is: no copy.
    bool all_inside = true;
    for (std::size_t j = 0; j < n && all_inside; ++j) all_inside = inside(poly[j]);
    if (all_inside) return;
    out.clear(), out_sides.clear();
    for (std::size_t j = 0; j < n; ++j) {
      const ClipPoint& P = poly[j];
      const ClipPoint& Q = poly[(j + 1) % n];
      const Side& side = sides[j];
      const bool in_p = inside(P), in_q = inside(Q);
      if (in_p) out.push_back(P), out_sides.push_back(side);
      if (in_p == in_q) continue;
      out.push_back(side.on_plane ? line_point(side.axis, side.plane, axis, x) : edge_cut(side.a, side.b, axis, x));
      Side next = side;
      if (in_p) next = Side{true, axis, x, 0, 0};
      out_sides.push_back(next);
    }
    poly.swap(out);
    sides.swap(out_sides);
  }
};

std::uint64_t cell_key(const ClipPoint& c, const MultilodGrid& grid) {
  const int cls = c.kind == 1 ? 1 + c.axis[0] : 4 + (3 - c.axis[0] - c.axis[1]);
  std::uint64_t key = static_cast<std::uint64_t>(cls) << kClassShift;
  for (int d = 0; d < 3; ++d) {
    const double cell = std::floor(static_cast<double>(c.p[d]) - grid.grid_origin[d]);
    if (!(cell >= 0 && cell < static_cast<double>(1 << kCellBits)))
      throw LimitError("labels: a surface point at " + std::to_string(c.p[d]) + " is past the supported " +
                       std::to_string((1 << kCellBits) - 2) + " samples along an axis of a multilod output");
    key |= static_cast<std::uint64_t>(cell) << (kRankBits + kCellBits * d);
  }
  return key;
}

// A corner of the clipped triangles: a surface point (its index in the
// surface) or a point the clipping made (its index in the made points).
struct Corner {
  std::uint32_t index = 0;
  bool made = false;
};

// The corners welded by key: each corner's point and the points' keys,
// increasing.
struct CornerWeld {
  std::vector<std::uint32_t> point;
  std::vector<std::uint64_t> keys;
};

using KeyedPoint = std::pair<std::uint64_t, std::uint32_t>;

// The distinct surface points among the corners, increasing (a bitmap over
// the span of their indices), and each corner's rank among them (a lookup
// table over the span, written only where a point is). Most corners are
// surface points, ~6 a point: the welding is by their 32-bit index.
struct DistinctPoints {
  std::vector<std::uint32_t> points;
  std::vector<std::uint32_t> rank;  // per surface corner, in corner order
};

DistinctPoints distinct_surface_points(const std::vector<Corner>& corners) {
  DistinctPoints out;
  std::uint32_t lo = std::numeric_limits<std::uint32_t>::max(), hi = 0;
  for (const Corner& c : corners)
    if (!c.made) lo = std::min(lo, c.index), hi = std::max(hi, c.index);
  if (lo > hi) return out;
  const std::size_t span = static_cast<std::size_t>(hi - lo) + 1;
  std::vector<std::uint64_t> present((span + 63) / 64, 0);
  for (const Corner& c : corners)
    if (!c.made) present[(c.index - lo) >> 6] |= std::uint64_t{1} << ((c.index - lo) & 63);
  const std::unique_ptr<std::uint32_t[]> rank_at(new std::uint32_t[span]);  // read only where written
  for (std::size_t w = 0; w < present.size(); ++w)
    for (std::uint64_t bits = present[w]; bits != 0; bits &= bits - 1) {
      const std::size_t local = 64 * w + static_cast<std::size_t>(std::countr_zero(bits));
      rank_at[local] = static_cast<std::uint32_t>(out.points.size());
      out.points.push_back(lo + static_cast<std::uint32_t>(local));
    }
  out.rank.reserve(corners.size());
  for (const Corner& c : corners)
    if (!c.made) out.rank.push_back(rank_at[c.index - lo]);
  return out;
}

// The surface points among the corners, deduplicated by index first, so that
// only the distinct points' 64-bit keys are put in key order. Appends their
// keys (class 0, below every made point's) to weld.keys.
void weld_surface_corners(const SegmentSurface& s, const std::vector<Corner>& corners, CornerWeld& weld) {
  const DistinctPoints distinct = distinct_surface_points(corners);
  if (distinct.points.empty()) return;
  // In index order the keys come in a few increasing runs (a surface numbers
  // its points in key order within each kind: surface nets' cell points,
  // then its face points): merged, not sorted.
  std::vector<std::uint64_t> keys(distinct.points.size());
  for (std::size_t u = 0; u < keys.size(); ++u) keys[u] = s.keys[distinct.points[u]];
  auto g = keyreduce::partition_runs(keys.data(), static_cast<Id>(keys.size()), keyreduce::Order::Skip);
  weld.keys = std::move(g.unique_keys);
  if (weld.keys.back() >> kClassShift != 0)
    throw std::logic_error("labels: internal error: a surface point's key has class bits set");
  std::size_t j = 0;
  for (std::size_t c = 0; c < corners.size(); ++c)
    if (!corners[c].made) weld.point[c] = g.index_map[distinct.rank[j++]];
}

// The made points' keys: the cell's key and the point's rank there among the
// distinct made points by name (one point per name). Appends them to
// weld.keys, increasing (their classes put them after the surface points).
void weld_made_corners(const std::vector<ClipPoint>& made, const std::vector<Corner>& corners, const MultilodGrid& grid,
                       CornerWeld& weld) {
  std::vector<KeyedPoint> order;  // (cell key, made point)
  order.reserve(made.size());
  for (std::size_t m = 0; m < made.size(); ++m) order.emplace_back(cell_key(made[m], grid), static_cast<std::uint32_t>(m));
  std::sort(order.begin(), order.end(), [&](const KeyedPoint& x, const KeyedPoint& y) {
    return x.first != y.first ? x.first < y.first : made[x.second].name() < made[y.second].name();
  });
  std::vector<std::uint32_t> point_of(made.size());
  std::uint64_t rank = 0;
  for (std::size_t m = 0; m < order.size(); ++m) {
    const bool same_cell = m > 0 && order[m].first == order[m - 1].first;
    const bool same_point = same_cell && made[order[m].second].name() == made[order[m - 1].second].name();
    rank = !same_cell ? 0 : same_point ? rank : rank + 1;
    if (rank >= (1u << kRankBits))
      throw LimitError("labels: more than 128 points made by clipping in one cell of a multilod output");
    if (!same_point) weld.keys.push_back(order[m].first | rank);
    point_of[order[m].second] = static_cast<std::uint32_t>(weld.keys.size() - 1);
  }
  for (std::size_t c = 0; c < corners.size(); ++c)
    if (corners[c].made) weld.point[c] = point_of[corners[c].index];
}

// The corners of the triangles clipped to the box [lo, hi], 3 a triangle,
// and the points the clipping made (once per polygon that has them).
void clip_triangles(const SegmentSurface& s, const MultilodGrid& grid, const double* lo, const double* hi,
                    const std::uint32_t* triangles, Id count, std::vector<Corner>& corners, std::vector<ClipPoint>& made) {
  corners.reserve(3 * static_cast<std::size_t>(count));  // most triangles lie inside: 3 corners each
  std::vector<ClipPoint> poly, clipped;
  std::vector<Side> sides, clipped_sides;
  std::vector<Corner> poly_corners;
  for (Id j = 0; j < count; ++j) {
    const std::uint32_t* t = s.triangles.data() + 3 * static_cast<std::size_t>(triangles[j]);
    Clipper clipper{s, grid, {t[0], t[1], t[2]}, lo, hi};
    bool inside = true;
    for (int m = 0; m < 3; ++m)
      for (int d = 0; d < 3; ++d) inside = inside && clipper.at(t[m])[d] > lo[d] && clipper.at(t[m])[d] < hi[d];
    if (inside) {  // its own corners, as the fan of the unclipped polygon below would give them
      for (int m = 0; m < 3; ++m) corners.push_back(Corner{t[m], false});
      continue;
    }
    std::sort(clipper.tri, clipper.tri + 3, [&](std::uint32_t a, std::uint32_t b) { return s.keys[a] < s.keys[b]; });
    poly.clear(), sides.clear();
    for (int m = 0; m < 3; ++m) {
      poly.push_back(clipper.surface_point(t[m]));
      sides.push_back(Side{false, 0, 0, t[m], t[(m + 1) % 3]});
    }
    for (int d = 0; d < 3; ++d) {
      clipper.clip(poly, sides, clipped, clipped_sides, d, lo[d], false);
      clipper.clip(poly, sides, clipped, clipped_sides, d, hi[d], true);
    }
    if (poly.size() < 3) continue;
    poly_corners.clear();
    for (const ClipPoint& p : poly) {
      poly_corners.push_back(p.kind == 0 ? Corner{p.index, false} : Corner{static_cast<std::uint32_t>(made.size()), true});
      if (p.kind != 0) made.push_back(p);
    }
    for (std::size_t m = 1; m + 1 < poly.size(); ++m) {  // a fan from the first point
      corners.push_back(poly_corners[0]);
      corners.push_back(poly_corners[m]);
      corners.push_back(poly_corners[m + 1]);
    }
  }
}

}  // namespace

float off_chunk_planes(const MultilodGrid& grid, int axis, float v, double margin) {
  const double cs = static_cast<double>(grid.chunk_shape[axis]);
  const double plane = grid.grid_origin[axis] + cs * std::round((static_cast<double>(v) - grid.grid_origin[axis]) / cs);
  const double d = static_cast<double>(v) - plane;
  if (std::abs(d) >= margin) return v;
  return static_cast<float>(d > 0 ? plane + margin : plane - margin);
}

void move_off_chunk_planes(SegmentSurface& surface, const MultilodGrid& grid) {
  double margin[3], near[3];  // near: a fraction of a chunk that holds the margin twice over
  for (int a = 0; a < 3; ++a)
    margin[a] = grid.margin(a, 0), near[a] = 2 * margin[a] / static_cast<double>(grid.chunk_shape[a]);
  for (std::size_t i = 0; i < surface.points.size(); ++i) {
    const int axis = static_cast<int>(i % 3);
    float& v = surface.points[i];
    // Most coordinates lie far from every plane: their position in units of
    // chunks, rounded toward zero, says so without the exact test (which
    // would leave them as they are).
    const double q = (static_cast<double>(v) - grid.grid_origin[axis]) / static_cast<double>(grid.chunk_shape[axis]);
    if (std::abs(q) < 0x1p52) {
      const double frac = std::abs(q - static_cast<double>(static_cast<std::int64_t>(q)));
      if (frac > near[axis] && 1 - frac > near[axis]) continue;
    }
    v = off_chunk_planes(grid, axis, v, margin[axis]);
  }
}

namespace {

// The chunk index along `axis` of the coordinate v (clamped to the grid).
std::uint32_t chunk_along(const MultilodGrid& grid, int axis, float v) {
  const double c = std::floor((static_cast<double>(v) - grid.grid_origin[axis]) / static_cast<double>(grid.chunk_shape[axis]));
  return static_cast<std::uint32_t>(std::clamp<Id>(static_cast<Id>(c), 0, grid.chunks[axis] - 1));
}

}  // namespace

ChunkTriangles triangles_by_chunk(const SegmentSurface& s, const MultilodGrid& grid) {
  // Each point's chunk along each axis, once: a triangle's chunk range is
  // then the least and greatest of its corners' (the index is monotone in
  // the coordinate).
  std::vector<std::uint32_t> along(s.points.size());
  for (std::size_t i = 0; i < along.size(); ++i) along[i] = chunk_along(grid, static_cast<int>(i % 3), s.points[i]);
  std::vector<std::uint64_t> chunk_of;  // one pair per (chunk, triangle)
  std::vector<std::uint32_t> triangle_of;
  const Id triangles = static_cast<Id>(s.triangles.size() / 3);
  chunk_of.reserve(static_cast<std::size_t>(triangles + triangles / 4));
  triangle_of.reserve(chunk_of.capacity());
  for (Id t = 0; t < triangles; ++t) {
    const std::uint32_t* corner = s.triangles.data() + 3 * t;
    Id lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      const std::uint32_t a = along[3 * static_cast<std::size_t>(corner[0]) + d], b = along[3 * static_cast<std::size_t>(corner[1]) + d],
                          c = along[3 * static_cast<std::size_t>(corner[2]) + d];
      lo[d] = std::min({a, b, c}), hi[d] = std::max({a, b, c});
    }
    for (Id z = lo[2]; z <= hi[2]; ++z)
      for (Id y = lo[1]; y <= hi[1]; ++y)
        for (Id x = lo[0]; x <= hi[0]; ++x) {
          chunk_of.push_back(static_cast<std::uint64_t>(x + grid.chunks[0] * (y + grid.chunks[1] * z)));
          triangle_of.push_back(static_cast<std::uint32_t>(t));
        }
  }
  ChunkTriangles out;
  const std::uint64_t top = chunk_of.empty() ? 0 : *std::max_element(chunk_of.begin(), chunk_of.end());
  const auto g = keyreduce::partition_dense(chunk_of.data(), static_cast<Id>(chunk_of.size()), top + 1,
                                            keyreduce::Order::Build);
  out.offsets.assign(g.offsets.begin(), g.offsets.end());
  if (out.offsets.empty()) out.offsets.push_back(0);
  for (std::uint64_t c : g.unique_keys) out.chunk.push_back(static_cast<Id>(c));
  out.triangles.resize(triangle_of.size());
  for (std::size_t j = 0; j < g.order.size(); ++j) out.triangles[j] = triangle_of[g.order[j]];
  return out;
}

MultilodPiece clip_to_chunk(const SegmentSurface& s, const MultilodGrid& grid, const std::array<Id, 3>& chunk,
                         const std::uint32_t* triangles, Id count) {
  double lo[3], hi[3];
  for (int d = 0; d < 3; ++d) lo[d] = grid.plane(d, chunk[d]), hi[d] = grid.plane(d, chunk[d] + 1);
  std::vector<Corner> corners;
  std::vector<ClipPoint> made;
  clip_triangles(s, grid, lo, hi, triangles, count, corners, made);
  MultilodPiece piece;
  piece.segment = s.segment;
  for (int d = 0; d < 3; ++d) piece.chunk[d] = static_cast<std::uint32_t>(chunk[d]);
  if (corners.empty()) return piece;
  CornerWeld weld;
  weld.point.resize(corners.size());
  weld_surface_corners(s, corners, weld);
  weld_made_corners(made, corners, grid, weld);
  piece.point_keys = std::move(weld.keys);
  piece.points.resize(3 * piece.point_keys.size());
  for (std::size_t c = 0; c < corners.size(); ++c) {
    const std::uint32_t i = corners[c].index;
    const float* p = corners[c].made ? made[i].p : s.points.data() + 3 * static_cast<std::size_t>(i);
    std::copy_n(p, 3, piece.points.begin() + 3 * static_cast<std::ptrdiff_t>(weld.point[c]));
  }
  piece.triangles = std::move(weld.point);
  return piece;
}

}  // namespace keymesh::generate::detail
