#include "keymesh/analyze/self_intersections.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include <omp.h>

#include "keymesh/analyze/exact_predicates.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"
#include "keymesh/parallel/threads.hpp"

namespace keymesh::analyze {

namespace {

using Tri = std::array<const float*, 3>;

bool same_position(const float* p, const float* q) { return p[0] == q[0] && p[1] == q[1] && p[2] == q[2]; }

// An axis along which the triangle projects with non-zero area (-1: none, the
// triangle has no area). Any such axis decides 2D tests in its plane exactly.
int projection_axis(const Tri& t) {
  for (int drop = 0; drop < 3; ++drop)
    if (orient2d(t[0], t[1], t[2], drop) != 0) return drop;
  return -1;
}

// p in the closed triangle t (p in t's plane; t projects with area along drop).
bool in_closed_triangle(const float* p, const Tri& t, int drop) {
  const int s = orient2d(t[0], t[1], t[2], drop);
  for (int k = 0; k < 3; ++k)
    if (orient2d(t[k], t[(k + 1) % 3], p, drop) == -s) return false;
  return true;
}

// Segments (p, q) and (r, s), in one plane, cross at a point inside both.
bool cross_properly(const float* p, const float* q, const float* r, const float* s, int drop) {
  if (orient2d(p, q, r, drop) * orient2d(p, q, s, drop) >= 0) return false;
  return orient2d(r, s, p, drop) * orient2d(r, s, q, drop) < 0;
}

// Edge (p, q) of one triangle against the closed triangle u: do they meet
// outside the corners the two triangles share? side_p, side_q: p's and q's
// sides of u's plane; *_shared: whether p, q are corners of u too.
bool edge_meets(const float* p, const float* q, int side_p, int side_q, bool p_shared, bool q_shared, const Tri& u,
                int drop) {
  if (p_shared && q_shared) return false;  // a common edge
  if (side_p * side_q > 0) return false;
  if (side_p == 0 && side_q == 0) {  // the edge lies in u's plane
    if (!p_shared && in_closed_triangle(p, u, drop)) return true;
    if (!q_shared && in_closed_triangle(q, u, drop)) return true;
    for (int k = 0; k < 3; ++k)
      if (cross_properly(p, q, u[k], u[(k + 1) % 3], drop)) return true;
    return false;  // a touch at one of u's corners shows from u's side
  }
  if (side_p == 0) return !p_shared && in_closed_triangle(p, u, drop);
  if (side_q == 0) return !q_shared && in_closed_triangle(q, u, drop);
  // The edge pierces u's plane at a point inside it: in u when it passes no
  // edge of u on the outside.
  bool positive = false, negative = false;
  for (int k = 0; k < 3; ++k) {
    const int o = orient3d(p, q, u[k], u[(k + 1) % 3]);
    positive |= o > 0;
    negative |= o < 0;
  }
  return !(positive && negative);
}

// triangles_cross with each triangle's projection axis already known.
bool cross_projected(const Tri& a, const Tri& b, int drop_a, int drop_b) {
  std::array<bool, 3> a_shared{}, b_shared{};
  int shared = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (same_position(a[i], b[j])) {
        a_shared[i] = b_shared[j] = true;
        ++shared;
      }
  if (shared >= 3) return true;  // the same triangle twice
  if (shared == 2) {
    // A common edge: out of one plane, the triangles meet only along it (most
    // pairs a mesh's broad phase gives are such neighbours: one predicate).
    const int other = !b_shared[0] ? 0 : !b_shared[1] ? 1 : 2;
    if (orient3d(a[0], a[1], a[2], b[other]) != 0) return false;
  }
  // When the corners one triangle does not share all lie strictly on one
  // side of the other's plane, it meets that plane only in the shared
  // corners (or their edge): no crossing. With one shared corner (a mesh's
  // broad phase gives many such fan neighbours) this ends the test after two
  // predicates.
  const int b_free = static_cast<int>(std::count(b_shared.begin(), b_shared.end(), false));
  const int a_free = static_cast<int>(std::count(a_shared.begin(), a_shared.end(), false));
  std::array<int, 3> side_b{}, side_a{};
  int b_above = 0, b_below = 0, a_above = 0, a_below = 0;
  for (int j = 0; j < 3; ++j) {
    // A common corner is on the other's plane: 0 without asking (exactly 0
    // is what the double filter cannot prove, so it would cost an exact sign).
    side_b[j] = b_shared[j] ? 0 : orient3d(a[0], a[1], a[2], b[j]);
    b_above += side_b[j] > 0;
    b_below += side_b[j] < 0;
  }
  if (b_above == b_free || b_below == b_free) return false;
  for (int i = 0; i < 3; ++i) {
    side_a[i] = a_shared[i] ? 0 : orient3d(b[0], b[1], b[2], a[i]);
    a_above += side_a[i] > 0;
    a_below += side_a[i] < 0;
  }
  if (a_above == a_free || a_below == a_free) return false;
  if (b_above == 0 && b_below == 0) {  // one plane: overlap in 2D
    for (int i = 0; i < 3; ++i)
      if (!a_shared[i] && in_closed_triangle(a[i], b, drop_a)) return true;
    for (int j = 0; j < 3; ++j)
      if (!b_shared[j] && in_closed_triangle(b[j], a, drop_a)) return true;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (cross_properly(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3], drop_a)) return true;
    return false;
  }
  // Two planes: the triangles meet on their common line, where some edge of
  // one reaches into the other.
  for (int i = 0; i < 3; ++i) {
    const int k = (i + 1) % 3;
    if (edge_meets(a[i], a[k], side_a[i], side_a[k], a_shared[i], a_shared[k], b, drop_b)) return true;
    if (edge_meets(b[i], b[k], side_b[i], side_b[k], b_shared[i], b_shared[k], a, drop_a)) return true;
  }
  return false;
}

}  // namespace

bool triangle_has_area(const Tri& t) { return projection_axis(t) >= 0; }

bool triangles_cross(const Tri& a, const Tri& b) { return cross_projected(a, b, projection_axis(a), projection_axis(b)); }

namespace {

struct Box {
  std::array<float, 3> lo, hi;
};

struct Broad {
  std::array<double, 3> origin{};
  double cell = 1;
  std::array<std::int64_t, 3> dims{1, 1, 1};

  std::array<std::int64_t, 3> cell_of(const std::array<float, 3>& p) const {
    std::array<std::int64_t, 3> c{};
    for (int k = 0; k < 3; ++k) {
      const double x = std::floor((double(p[k]) - origin[k]) / cell);
      c[k] = std::clamp<std::int64_t>(static_cast<std::int64_t>(std::max(0.0, std::min(x, 1e18))), 0, dims[k] - 1);
    }
    return c;
  }
  std::uint64_t key(const std::array<std::int64_t, 3>& c) const {
    return static_cast<std::uint64_t>(c[0] + dims[0] * (c[1] + dims[1] * c[2]));
  }
};

// Grid cells about twice the mean triangle extent, at most ~2 per triangle.
Broad make_broad(const std::vector<Box>& boxes) {
  Broad g;
  std::array<double, 3> lo{}, hi{};
  lo.fill(std::numeric_limits<double>::max());
  hi.fill(std::numeric_limits<double>::lowest());
  double extent = 0;
  for (const Box& b : boxes) {
    double e = 0;
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], double(b.lo[k]));
      hi[k] = std::max(hi[k], double(b.hi[k]));
      e = std::max(e, double(b.hi[k]) - b.lo[k]);
    }
    extent += e;
  }
  if (boxes.empty()) return g;
  g.origin = lo;
  const double n = static_cast<double>(boxes.size());
  double cell = std::max(2 * extent / n, 1e-30);
  for (;;) {
    double cells = 1;
    for (int k = 0; k < 3; ++k) cells *= std::floor((hi[k] - lo[k]) / cell) + 1;
    if (cells <= 2 * n + 8 && std::isfinite(cells)) break;
    cell *= 1.25;
  }
  g.cell = cell;
  for (int k = 0; k < 3; ++k) g.dims[k] = static_cast<std::int64_t>(std::floor((hi[k] - lo[k]) / cell)) + 1;
  return g;
}

bool boxes_overlap(const Box& a, const Box& b) {
  for (int k = 0; k < 3; ++k)
    if (a.hi[k] < b.lo[k] || b.hi[k] < a.lo[k]) return false;
  return true;
}


// The mesh's cells as fan triangles, each with its cell; point ids and
// coordinates checked.
struct FanTriangles {
  std::vector<std::array<PointIndex, 3>> tris;
  std::vector<Id> cell;
  const float* xyz = nullptr;

  Tri corners(std::size_t t) const {
    return Tri{xyz + 3 * std::size_t(tris[t][0]), xyz + 3 * std::size_t(tris[t][1]), xyz + 3 * std::size_t(tris[t][2])};
  }
};

FanTriangles fan_triangles(const SurfaceMesh& mesh) {
  FanTriangles f;
  const Id points = mesh.num_points(), cells = mesh.num_cells();
  for (Id c = 0; c < cells; ++c) {
    const std::uint64_t b = mesh.cell_begin(c), e = mesh.cell_end(c);
    for (std::uint64_t k = b; k < e; ++k)
      if (mesh.connectivity[k] >= static_cast<std::uint64_t>(points))
        throw InputError("cell " + std::to_string(c) + " refers to point " + std::to_string(mesh.connectivity[k]) +
                         " of " + std::to_string(points));
    for (std::uint64_t k = b + 1; k + 1 < e; ++k) {
      f.tris.push_back({mesh.connectivity[b], mesh.connectivity[k], mesh.connectivity[k + 1]});
      f.cell.push_back(c);
    }
  }
  f.xyz = mesh.points.data();
  for (Id p = 0; p < 3 * points; ++p)
    if (!std::isfinite(f.xyz[p]))
      throw InputError("point " + std::to_string(p / 3) + " has a coordinate that is not finite");
  return f;
}

// Every (grid cell, box) pair a box covers, sorted by grid cell, and where
// each grid cell's run of boxes starts (run_start ends with the pair count).
struct CellRuns {
  std::vector<std::uint64_t> keys;
  std::vector<std::uint32_t> members;
  std::vector<std::uint64_t> run_start;
};

CellRuns cell_runs(const Broad& grid, const std::vector<Box>& boxes) {
  CellRuns r;
  std::vector<std::uint64_t> count(boxes.size() + 1, 0);
  parallel::for_each(static_cast<Id>(boxes.size()), [&](Id i) {
    const auto lo = grid.cell_of(boxes[i].lo), hi = grid.cell_of(boxes[i].hi);
    count[i] = std::uint64_t(hi[0] - lo[0] + 1) * std::uint64_t(hi[1] - lo[1] + 1) * std::uint64_t(hi[2] - lo[2] + 1);
  });
  const std::uint64_t entries = parallel::exclusive_scan(count);
  r.keys.resize(entries);
  r.members.resize(entries);
  parallel::for_each(static_cast<Id>(boxes.size()), [&](Id i) {
    const auto lo = grid.cell_of(boxes[i].lo), hi = grid.cell_of(boxes[i].hi);
    std::uint64_t at = count[i];
    for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
        for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
          r.keys[at] = grid.key({x, y, z});
          r.members[at++] = static_cast<std::uint32_t>(i);
        }
  });
  parallel::sort_pairs(r.keys, r.members,
                       parallel::bits_needed(grid.key({grid.dims[0] - 1, grid.dims[1] - 1, grid.dims[2] - 1})));
  for (std::uint64_t e = 0; e < entries; ++e)
    if (e == 0 || r.keys[e] != r.keys[e - 1]) r.run_start.push_back(e);
  r.run_start.push_back(entries);
  return r;
}

}  // namespace

SelfIntersectionReport find_self_intersections(const SurfaceMesh& mesh, std::size_t max_listed) {
  SelfIntersectionReport report;
  const FanTriangles fan = fan_triangles(mesh);
  report.triangles = static_cast<Id>(fan.tris.size());
  std::vector<signed char> axis(fan.tris.size());  // projection axis, -1 without area
  parallel::for_each(static_cast<Id>(fan.tris.size()),
                     [&](Id t) { axis[t] = static_cast<signed char>(projection_axis(fan.corners(t))); });
  std::vector<std::uint32_t> live;
  for (std::size_t t = 0; t < fan.tris.size(); ++t)
    if (axis[t] >= 0) live.push_back(static_cast<std::uint32_t>(t));
  report.zero_area_triangles = report.triangles - static_cast<Id>(live.size());
  if (fan.tris.size() > std::numeric_limits<std::uint32_t>::max())
    throw LimitError("self-intersection check: more than 2^32 - 1 triangles");

  std::vector<Box> boxes(live.size());
  parallel::for_each(static_cast<Id>(live.size()), [&](Id i) {
    const Tri t = fan.corners(live[i]);
    for (int k = 0; k < 3; ++k) {
      boxes[i].lo[k] = std::min({t[0][k], t[1][k], t[2][k]});
      boxes[i].hi[k] = std::max({t[0][k], t[1][k], t[2][k]});
    }
  });
  const Broad grid = make_broad(boxes);
  const CellRuns runs = cell_runs(grid, boxes);
  // Each box's low grid cell: cell_of is monotone along every axis, so the
  // cell of two boxes' overlap's low corner is the larger of theirs, axis by
  // axis (no floor or division per pair).
  std::vector<std::array<std::int64_t, 3>> low_cell(boxes.size());
  parallel::for_each(static_cast<Id>(boxes.size()), [&](Id i) { low_cell[i] = grid.cell_of(boxes[i].lo); });

  // Each pair of boxes is tested once, in the grid cell holding the low
  // corner of their overlap.
  const int threads = parallel::thread_count();
  std::vector<std::vector<std::array<Id, 2>>> found(static_cast<std::size_t>(threads));
  const Id run_count = static_cast<Id>(runs.run_start.size()) - 1;
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads)
  for (Id r = 0; r < run_count; ++r) {
    auto& mine = found[static_cast<std::size_t>(omp_get_thread_num())];
    const std::uint64_t b = runs.run_start[r], e = runs.run_start[r + 1];
    for (std::uint64_t i = b; i < e; ++i)
      for (std::uint64_t j = i + 1; j < e; ++j) {
        const std::uint32_t u = runs.members[i], v = runs.members[j];
        const Id cu = fan.cell[live[u]], cv = fan.cell[live[v]];
        if (cu == cv || !boxes_overlap(boxes[u], boxes[v])) continue;
        std::array<std::int64_t, 3> low{};
        for (int k = 0; k < 3; ++k) low[k] = std::max(low_cell[u][k], low_cell[v][k]);
        if (grid.key(low) != runs.keys[b]) continue;  // tested in another grid cell
        if (cross_projected(fan.corners(live[u]), fan.corners(live[v]), axis[live[u]], axis[live[v]]))
          mine.push_back({std::min(cu, cv), std::max(cu, cv)});
      }
  }
  std::vector<std::array<Id, 2>> all;
  for (auto& f : found) all.insert(all.end(), f.begin(), f.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  report.self_intersections = static_cast<Id>(all.size());
  if (all.size() > max_listed) all.resize(max_listed);
  report.pairs = std::move(all);
  return report;
}

}  // namespace keymesh::analyze
