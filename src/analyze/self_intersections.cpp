#include "keymesh/analyze/self_intersections.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include <omp.h>
#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"
#include "keymesh/parallel/threads.hpp"
#include "triangle_crossing.hpp"

namespace keymesh::analyze {

namespace {

using detail::Tri;

// Up to this many triangles with area the automatic broad phase sweeps
// (serially): parallel::for_each runs such sizes serially too.
constexpr std::size_t kSweepLimit = 8192;

}  // namespace

bool triangle_has_area(const Tri& t) { return detail::projection_axis(t) >= 0; }

bool triangles_cross(const Tri& a, const Tri& b) {
  return detail::cross_projected(a, b, detail::projection_axis(a), detail::projection_axis(b));
}

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

// The fan triangles with area, in fan order, with what the pair test and
// the broad phases read per triangle.
struct LiveTriangles {
  std::vector<Tri> corners;
  std::vector<signed char> axis;  // projection axis
  std::vector<Id> cell;
  std::vector<Box> boxes;
  std::vector<detail::IntegerTriangle> integer;  // when the mesh's coordinates allow (triangle_crossing.hpp)

  std::size_t size() const { return corners.size(); }
  // Fan triangles of one polygon are not tested against each other.
  bool candidates(std::uint32_t u, std::uint32_t v) const {
    return cell[u] != cell[v] && boxes_overlap(boxes[u], boxes[v]);
  }
  bool cross(std::uint32_t u, std::uint32_t v) const {
    if (integer.empty()) return detail::cross_projected(corners[u], corners[v], axis[u], axis[v]);
    return detail::cross_projected(corners[u], corners[v], axis[u], axis[v], integer[u], integer[v]);
  }
  std::array<Id, 2> pair(std::uint32_t u, std::uint32_t v) const {
    return {std::min(cell[u], cell[v]), std::max(cell[u], cell[v])};
  }
};

// The projection axis (-1 without area) of each fan triangle; with integer
// coordinates also its integer triangle, whose normal gives the axis at no
// further cost: orient2d dropping axis k is the sign of normal[k].
void fan_axes(const FanTriangles& fan, bool integer, std::vector<signed char>& axis,
              std::vector<detail::IntegerTriangle>& integer_fan) {
  axis.resize(fan.tris.size());
  if (!integer) {
    parallel::for_each(static_cast<Id>(fan.tris.size()),
                       [&](Id t) { axis[t] = static_cast<signed char>(detail::projection_axis(fan.corners(t))); });
    return;
  }
  integer_fan.resize(fan.tris.size());
  parallel::for_each(static_cast<Id>(fan.tris.size()), [&](Id t) {
    integer_fan[t] = detail::integer_triangle(fan.corners(t));
    const auto& normal = integer_fan[t].normal;
    axis[t] = static_cast<signed char>(normal[0] != 0 ? 0 : normal[1] != 0 ? 1 : normal[2] != 0 ? 2 : -1);
  });
}

LiveTriangles live_triangles(const FanTriangles& fan, const SurfaceMesh& mesh) {
  std::vector<signed char> axis;
  std::vector<detail::IntegerTriangle> integer_fan;
  fan_axes(fan, detail::integer_coordinates(mesh.points.data(), mesh.points.size()), axis, integer_fan);
  LiveTriangles live;
  const std::size_t with_area = fan.tris.size() - static_cast<std::size_t>(std::count(axis.begin(), axis.end(), -1));
  live.corners.reserve(with_area);
  live.axis.reserve(with_area);
  live.cell.reserve(with_area);
  live.integer.reserve(integer_fan.empty() ? 0 : with_area);
  for (std::size_t t = 0; t < fan.tris.size(); ++t)
    if (axis[t] >= 0) {
      live.corners.push_back(fan.corners(t));
      live.axis.push_back(axis[t]);
      live.cell.push_back(fan.cell[t]);
      if (!integer_fan.empty()) live.integer.push_back(integer_fan[t]);
    }
  live.boxes.resize(live.size());
  parallel::for_each(static_cast<Id>(live.size()), [&](Id i) {
    const Tri& t = live.corners[i];
    for (int k = 0; k < 3; ++k) {
      live.boxes[i].lo[k] = std::min({t[0][k], t[1][k], t[2][k]});
      live.boxes[i].hi[k] = std::max({t[0][k], t[1][k], t[2][k]});
    }
  });
  return live;
}

// Threaded: each pair of overlapping boxes is tested once, in the grid cell
// holding the low corner of their overlap.
std::vector<std::array<Id, 2>> grid_crossings(const LiveTriangles& live) {
  const Broad grid = make_broad(live.boxes);
  const CellRuns runs = cell_runs(grid, live.boxes);
  // Each box's low grid cell: cell_of is monotone along every axis, so the
  // cell of two boxes' overlap's low corner is the larger of theirs, axis by
  // axis (no floor or division per pair).
  std::vector<std::array<std::int64_t, 3>> low_cell(live.size());
  parallel::for_each(static_cast<Id>(live.size()), [&](Id i) { low_cell[i] = grid.cell_of(live.boxes[i].lo); });
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
        if (!live.candidates(u, v)) continue;
        std::array<std::int64_t, 3> low{};
        for (int k = 0; k < 3; ++k) low[k] = std::max(low_cell[u][k], low_cell[v][k]);
        if (grid.key(low) != runs.keys[b]) continue;  // tested in another grid cell
        if (live.cross(u, v)) mine.push_back(live.pair(u, v));
      }
  }
  std::vector<std::array<Id, 2>> all;
  for (auto& f : found) all.insert(all.end(), f.begin(), f.end());
  return all;
}

// The axis along which a sweep meets the fewest boxes per box: the largest
// spread of the boxes' low ends against the boxes' summed extents.
int sweep_axis(const std::vector<Box>& boxes) {
  std::array<double, 3> lo{}, hi{}, extent{};
  lo.fill(std::numeric_limits<double>::max());
  hi.fill(std::numeric_limits<double>::lowest());
  for (const Box& b : boxes)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], double(b.lo[k]));
      hi[k] = std::max(hi[k], double(b.lo[k]));
      extent[k] += double(b.hi[k]) - b.lo[k];
    }
  int best = 0;
  for (int k = 1; k < 3; ++k)  // spread[k] / extent[k] > spread[best] / extent[best]
    if ((hi[k] - lo[k]) * extent[best] > (hi[best] - lo[best]) * extent[k]) best = k;
  return best;
}

// Boxes the sweep compares with one box at a time.
constexpr std::size_t kLanes = 4;

// The boxes in sweep order, apart (structure of arrays): the sweep finds
// where the boxes starting before a box ends stop by bisecting start, then
// compares kLanes of them at a time along the other two axes p, q. across
// holds lo_p, lo_q, -hi_p, -hi_q (padded with +inf by kLanes - 1), reach
// each box's hi_p, hi_q, -lo_p, -lo_q: boxes i and j overlap across when
// across[k][j] <= reach[i][k] for all four k (negation is exact, so the
// answers are the plain comparisons').
struct SweepBoxes {
  std::vector<float> start, end;
  std::array<std::vector<float>, 4> across;
  std::vector<std::array<float, 4>> reach;
  std::vector<std::uint32_t> triangle;  // the live triangle
  std::vector<Id> cell;                 // its cell
};

SweepBoxes sweep_boxes(const LiveTriangles& live) {
  const std::size_t n = live.size();
  const int axis = sweep_axis(live.boxes), p = (axis + 1) % 3, q = (axis + 2) % 3;
  SweepBoxes s;
  s.triangle.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) s.triangle[i] = i;
  std::sort(s.triangle.begin(), s.triangle.end(),
            [&](std::uint32_t a, std::uint32_t b) { return live.boxes[a].lo[axis] < live.boxes[b].lo[axis]; });
  s.start.resize(n);
  s.end.resize(n);
  for (auto& lane : s.across) lane.assign(n + kLanes - 1, std::numeric_limits<float>::infinity());
  s.reach.resize(n);
  s.cell.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Box& b = live.boxes[s.triangle[i]];
    s.start[i] = b.lo[axis];
    s.end[i] = b.hi[axis];
    const std::array<float, 4> across{b.lo[p], b.lo[q], -b.hi[p], -b.hi[q]};
    for (std::size_t k = 0; k < 4; ++k) s.across[k][i] = across[k];
    s.reach[i] = {b.hi[p], b.hi[q], -b.lo[p], -b.lo[q]};
    s.cell[i] = live.cell[s.triangle[i]];
  }
  return s;
}

// Which of the boxes j to j + kLanes - 1 overlap a box across (bit l: box
// j + l), given that box's reach.
#if defined(__SSE__)
struct Reach {
  __m128 lanes[4];  // a plain array: std::array drops __m128's alignment attributes
  explicit Reach(const std::array<float, 4>& r) {
    for (std::size_t k = 0; k < 4; ++k) lanes[k] = _mm_set1_ps(r[k]);
  }
};
unsigned overlap_lanes(const SweepBoxes& s, std::size_t j, const Reach& reach) {
  __m128 in = _mm_cmple_ps(_mm_loadu_ps(&s.across[0][j]), reach.lanes[0]);
  for (std::size_t k = 1; k < 4; ++k) in = _mm_and_ps(in, _mm_cmple_ps(_mm_loadu_ps(&s.across[k][j]), reach.lanes[k]));
  return static_cast<unsigned>(_mm_movemask_ps(in));
}
#else
struct Reach {
  std::array<float, 4> r;
  explicit Reach(const std::array<float, 4>& v) : r(v) {}
};
unsigned overlap_lanes(const SweepBoxes& s, std::size_t j, const Reach& reach) {
  unsigned mask = 0;
  for (std::size_t l = 0; l < kLanes; ++l) {
    bool in = true;
    for (std::size_t k = 0; k < 4; ++k) in = in && s.across[k][j + l] <= reach.r[k];
    mask |= unsigned(in) << l;
  }
  return mask;
}
#endif

// Serial sort and sweep: boxes in order of their low ends along one axis,
// each checked against those that start before it ends. For small meshes,
// where the grid's sort and thread start cost more than the pairs.
std::vector<std::array<Id, 2>> sweep_crossings(const LiveTriangles& live) {
  const SweepBoxes s = sweep_boxes(live);
  const std::size_t n = s.start.size();
  std::vector<std::array<Id, 2>> found;
  for (std::size_t i = 0; i < n; ++i) {
    // The boxes from i + 1 to stop start before box i ends.
    const std::size_t stop = static_cast<std::size_t>(
        std::upper_bound(s.start.begin() + static_cast<std::ptrdiff_t>(i + 1), s.start.end(), s.end[i]) -
        s.start.begin());
    const Reach reach(s.reach[i]);
    for (std::size_t j = i + 1; j < stop; j += kLanes) {
      unsigned mask = overlap_lanes(s, j, reach);
      if (stop - j < kLanes) mask &= (1u << (stop - j)) - 1;
      for (; mask != 0; mask &= mask - 1) {
        const std::size_t k = j + static_cast<std::size_t>(std::countr_zero(mask));
        if (s.cell[k] == s.cell[i]) continue;
        const std::uint32_t u = s.triangle[i], v = s.triangle[k];
        if (live.cross(u, v)) found.push_back(live.pair(u, v));
      }
    }
  }
  return found;
}

}  // namespace

SelfIntersectionReport find_self_intersections(const SurfaceMesh& mesh, std::size_t max_listed, BroadPhase broad) {
  SelfIntersectionReport report;
  const FanTriangles fan = fan_triangles(mesh);
  if (fan.tris.size() > std::numeric_limits<std::uint32_t>::max())
    throw LimitError("self-intersection check: more than 2^32 - 1 triangles");
  report.triangles = static_cast<Id>(fan.tris.size());
  const LiveTriangles live = live_triangles(fan, mesh);
  report.zero_area_triangles = report.triangles - static_cast<Id>(live.size());
  if (broad == BroadPhase::automatic) broad = live.size() <= kSweepLimit ? BroadPhase::sweep : BroadPhase::grid;
  std::vector<std::array<Id, 2>> all = broad == BroadPhase::sweep ? sweep_crossings(live) : grid_crossings(live);
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  report.self_intersections = static_cast<Id>(all.size());
  if (all.size() > max_listed) all.resize(max_listed);
  report.pairs = std::move(all);
  return report;
}

}  // namespace keymesh::analyze
