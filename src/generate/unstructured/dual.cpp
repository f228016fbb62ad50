#include "keymesh/generate/unstructured/dual.hpp"

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "keymesh/analyze/incidence.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/core/progress.hpp"
#include "keymesh/generate/unstructured/dual_kernels.hpp"
#include "keymesh/mesh/fields.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh::generate {

namespace {

// A thread's scratch for fans_of, reused from point to point: the fan being
// walked, and per incident corner whether it is used, its link's ends and
// its place in the walk.
struct FanScratch {
  std::vector<std::uint32_t> fan, order;
  std::vector<std::uint8_t> used;
  std::vector<PointIndex> next, prev;
};

// Around point p, each incident corner of cell c gives the link a -> b
// between the corner's next and previous points. The fans of p are the
// chains of links (dual_kernels::walk_fans, the device path's walk too);
// `visit(fan_corners, open)` is called for each fan with its corners in
// walking order. The links are looked up once per corner first.
template <class Visit>
void fans_of(const SurfaceMesh& m, const analyze::PointCells& pc, Id p, FanScratch& sc, Visit&& visit) {
  const Id b = pc.offsets[p], k = pc.count(p);
  const auto n = static_cast<std::size_t>(k);
  sc.used.resize(n);
  sc.order.resize(n);
  sc.next.resize(n);
  sc.prev.resize(n);
  for (Id i = 0; i < k; ++i) {
    const std::uint32_t corner = pc.corners[b + i];
    const std::uint32_t c = pc.cell_of(corner);
    const std::uint64_t begin = m.cell_begin(c), end = m.cell_end(c);
    sc.next[i] = m.connectivity[corner + 1 < end ? corner + 1 : begin];
    sc.prev[i] = m.connectivity[corner > begin ? corner - 1 : end - 1];
  }
  dual_kernels::walk_fans(k, sc.next.data(), sc.prev.data(), sc.used.data(), sc.order.data(),
                          [&](Id first, Id size, bool open) {
                            sc.fan.clear();
                            for (Id i = first; i < first + size; ++i) sc.fan.push_back(pc.corners[b + sc.order[i]]);
                            visit(sc.fan, open);
                          });
}

// dual_kernels::fan_is_polygon for a walked fan.
bool fan_is_polygon(const std::vector<std::uint32_t>& f, bool open) {
  return dual_kernels::fan_is_polygon(static_cast<Id>(f.size()), open);
}

// Pass 1 of the dual, by chunks of points: what each chunk contributes
// (polygons, their corners, own points: copies of the points with an open
// fan), scanned into every chunk's first indices, and the fan statistics.
// Per point only whether it has an own point is kept (one byte); the
// polygon pass walks the fans again and numbers them as it goes, so no
// per-point counts are held beside the output.
struct FanCounts {
  std::vector<std::uint8_t> has_own_point;                   // per point
  std::vector<Id> first_poly, first_corner, first_own_point;  // per chunk, + the totals
  Id polys = 0, corners = 0, extra = 0;
  DualStats stats;
};

FanCounts count_fans(const SurfaceMesh& m, const analyze::PointCells& pc, int chunks) {
  const Id V = m.num_points();
  FanCounts fc;
  fc.has_own_point.assign(static_cast<std::size_t>(V), 0);
  for (auto* v : {&fc.first_poly, &fc.first_corner, &fc.first_own_point}) v->assign(static_cast<std::size_t>(chunks + 1), 0);
  std::vector<DualStats> chunk_stats(static_cast<std::size_t>(chunks));
  parallel::for_each_chunk(V, chunks, [&](Id lo, Id hi, int c) {
    FanScratch scratch;
    DualStats& st = chunk_stats[c];
    for (Id p = lo; p < hi; ++p) {
      Id fans = 0;
      fans_of(m, pc, p, scratch, [&](const std::vector<std::uint32_t>& f, bool open) {
        ++fans;
        st.boundary_fans += open;
        if (!fan_is_polygon(f, open)) {
          ++st.skipped_fans;
          return;
        }
        ++fc.first_poly[c];
        fc.first_corner[c] += static_cast<Id>(f.size()) + (open ? 1 : 0);
        if (open) fc.has_own_point[p] = 1;
      });
      st.nonmanifold_points += fans > 1;
      fc.first_own_point[c] += fc.has_own_point[p];
    }
  });
  fc.polys = parallel::exclusive_scan(fc.first_poly.data(), fc.first_poly.data(), chunks + 1);
  fc.corners = parallel::exclusive_scan(fc.first_corner.data(), fc.first_corner.data(), chunks + 1);
  fc.extra = parallel::exclusive_scan(fc.first_own_point.data(), fc.first_own_point.data(), chunks + 1);
  fc.stats.polygons = fc.polys;
  for (const DualStats& st : chunk_stats) {
    fc.stats.boundary_fans += st.boundary_fans;
    fc.stats.nonmanifold_points += st.nonmanifold_points;
    fc.stats.skipped_fans += st.skipped_fans;
  }
  return fc;
}

// The dual's points: every cell's centroid (fields averaged alike, normals
// renormalised), then a copy of every point with an open fan. Arrays sized
// once (mesh/fields.hpp) and written in place.
void dual_points(const SurfaceMesh& m, const FanCounts& fc, int chunks, SurfaceMesh& out) {
  const Id V = m.num_points(), F = m.num_cells();
  parallel::resize_fresh(out.points, static_cast<std::size_t>(3 * (F + fc.extra)));
  out.point_fields = new_point_fields(m.point_fields, F + fc.extra);
  std::vector<std::uint8_t> renormalise(m.point_fields.size());
  for (std::size_t i = 0; i < m.point_fields.size(); ++i)
    renormalise[i] = m.point_fields[i].name == "Normals" && m.point_fields[i].components == 3;
  parallel::for_each(F, [&](Id c) {
    const std::uint64_t b = m.cell_begin(c), e = m.cell_end(c);
    dual_kernels::centroid_tuple(m.connectivity.data(), b, e, m.points.data(), 3, false, &out.points[3 * c]);
    for (std::size_t i = 0; i < m.point_fields.size(); ++i) {
      const Field& f = m.point_fields[i];
      dual_kernels::centroid_tuple(m.connectivity.data(), b, e, f.values.data(), f.components, renormalise[i] != 0,
                                   &out.point_fields[i].values[c * f.components]);
    }
  });
  parallel::for_each_chunk(V, chunks, [&](Id lo, Id hi, int chunk) {
    Id q = F + fc.first_own_point[chunk];
    for (Id p = lo; p < hi; ++p) {
      if (!fc.has_own_point[p]) continue;
      for (int x = 0; x < 3; ++x) out.points[3 * q + x] = m.points[3 * p + x];
      for (std::size_t i = 0; i < m.point_fields.size(); ++i) {
        const int k = m.point_fields[i].components;
        std::copy_n(m.point_fields[i].values.begin() + p * k, k, out.point_fields[i].values.begin() + q * k);
      }
      ++q;
    }
  });
}

// Pass 2: the polygons, point by point (so in input point order), numbered
// from each chunk's first indices.
void dual_polygons(const SurfaceMesh& m, const analyze::PointCells& pc, const FanCounts& fc, int chunks,
                   SurfaceMesh& out) {
  const Id V = m.num_points(), F = m.num_cells();
  parallel::resize_fresh(out.connectivity, static_cast<std::size_t>(fc.corners));
  parallel::resize_fresh(out.offsets, static_cast<std::size_t>(fc.polys + 1));
  out.offsets[fc.polys] = static_cast<std::uint64_t>(fc.corners);
  parallel::for_each_chunk(V, chunks, [&](Id lo, Id hi, int c) {
    FanScratch scratch;
    Id poly = fc.first_poly[c], at = fc.first_corner[c], own_point = F + fc.first_own_point[c];
    for (Id p = lo; p < hi; ++p) {
      fans_of(m, pc, p, scratch, [&](const std::vector<std::uint32_t>& f, bool open) {
        if (!fan_is_polygon(f, open)) return;
        out.offsets[poly++] = static_cast<std::uint64_t>(at);
        for (std::uint32_t corner : f) out.connectivity[at++] = pc.cell_of(corner);
        if (open) out.connectivity[at++] = static_cast<PointIndex>(own_point);
      });
      own_point += fc.has_own_point[p];
    }
  });
}

}  // namespace

void check_dual_input(const SurfaceMesh& mesh) { analyze::check_ids(mesh); }

SurfaceMesh dual(const SurfaceMesh& m, DualStats* stats) {
  const analyze::PointCells pc = analyze::point_cells(m);
  const Id V = m.num_points(), F = m.num_cells();
  progress::report("dual: fans", 0.0);
  const int chunks = parallel::chunk_count(V, 1024);
  const FanCounts fc = count_fans(m, pc, chunks);
  if (F + fc.extra > Id{UINT32_MAX} || fc.corners > Id{UINT32_MAX})
    throw LimitError("dual: " + std::to_string(F + fc.extra) + " points or " + std::to_string(fc.corners) +
                     " corners exceed 2^32 - 1");
  SurfaceMesh out;
  dual_points(m, fc, chunks, out);
  progress::report("dual: polygons", 0.5);
  dual_polygons(m, pc, fc, chunks, out);
  if (stats) *stats = fc.stats;
  return out;
}

}  // namespace keymesh::generate
