#pragma once
// The dual of a polygon surface (dual.hpp) over the device layer
// (keymesh/device/), written once for every device:
//   every corner keyed by its point -> KEY-REDUCE's grouping (stable radix
//   sort + run-length: each point's corners in increasing order, the
//   incidence dual.cpp walks) -> each corner's link (next and previous point
//   of its cell) -> one thread per point walks its fans and counts polygons,
//   corners and own points (dual_kernels.hpp, the CPU path's walk) ->
//   exclusive scans (64-bit) -> one thread per point walks them again and
//   writes its polygons -> every cell's centroid and the points with an open
//   fan, fields alike (dual_kernels::centroid_tuple).
// Equal to dual() bit for bit, statistics included (ctest runs it on the CPU
// device: tests/generate/unstructured/dual_device_test.cpp).
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/analyze/incidence.hpp"
#include "keymesh/core/device.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/device/algorithms.hpp"
#include "keymesh/device/key_groups.hpp"
#include "keymesh/parallel/bits_needed.hpp"
#include "keymesh/generate/unstructured/dual.hpp"
#include "keymesh/generate/unstructured/dual_kernels.hpp"

namespace keymesh::generate {

// dual() through the device path on the CPU device.
SurfaceMesh dual_on_cpu_device(const SurfaceMesh& mesh, DualStats* stats = nullptr);

namespace device_dual {

// Cell c's corners [begin(c), end(c)): triangles when offsets is null.
struct Cells {
  const std::uint64_t* offsets;
  KEYMESH_HD std::uint64_t begin(Id c) const { return offsets ? offsets[c] : 3 * static_cast<std::uint64_t>(c); }
  KEYMESH_HD std::uint64_t end(Id c) const { return offsets ? offsets[c + 1] : 3 * static_cast<std::uint64_t>(c) + 3; }
};

// Every corner's cell.
struct CellOfCorner {
  Cells cells;
  std::uint32_t* cell_of;
  KEYMESH_HD void operator()(Id c) const {
    for (std::uint64_t k = cells.begin(c); k < cells.end(c); ++k) cell_of[k] = static_cast<std::uint32_t>(c);
  }
};

// first[p] = the number of corners of point p (scanned afterwards into
// each point's first sorted position); points no cell uses keep 0.
struct CornerCounts {
  const PointIndex* points;  // the grouping's keys
  const Id* offsets;
  Id* first;
  KEYMESH_HD void operator()(Id g) const { first[points[g]] = offsets[g + 1] - offsets[g]; }
};

// The link of the corner at sorted position j: its cell's next and
// previous points.
struct Links {
  const PointIndex* conn;
  Cells cells;
  const std::uint32_t* corners;  // per sorted position
  const std::uint32_t* cell_of;
  PointIndex* next;
  PointIndex* prev;
  KEYMESH_HD void operator()(Id j) const {
    const std::uint32_t corner = corners[j], c = cell_of[corner];
    const std::uint64_t begin = cells.begin(c), end = cells.end(c);
    next[j] = conn[corner + 1 < end ? corner + 1 : begin];
    prev[j] = conn[corner > begin ? corner - 1 : end - 1];
  }
};

// A point's fans, over its span of the per-sorted-position arrays (which
// the point owns: `used` and `order` are its scratch).
struct Fans {
  const Id* first;
  const PointIndex* next;
  const PointIndex* prev;
  std::uint8_t* used;
  std::uint32_t* order;
  template <class Visit>
  KEYMESH_HD void walk(Id p, Visit&& visit) const {
    const Id b = first[p];
    dual_kernels::walk_fans(first[p + 1] - b, next + b, prev + b, used + b, order + b,
                            [&](Id f, Id size, bool open) { visit(order + b + f, size, open); });
  }
};

// Pass 1, per point: its polygons, their corners, whether it has an own
// point (an open fan that is a polygon), and its fan statistics.
struct CountFans {
  Fans fans;
  Id* polys;
  Id* corners;
  Id* own;
  Id* boundary_fans;
  Id* skipped_fans;
  Id* nonmanifold;
  KEYMESH_HD void operator()(Id p) const {
    Id n_fans = 0, n_polys = 0, n_corners = 0, n_boundary = 0, n_skipped = 0, has_own = 0;
    fans.walk(p, [&](const std::uint32_t*, Id size, bool open) {
      ++n_fans;
      n_boundary += open;
      if (!dual_kernels::fan_is_polygon(size, open)) {
        ++n_skipped;
        return;
      }
      ++n_polys;
      n_corners += size + (open ? 1 : 0);
      if (open) has_own = 1;
    });
    polys[p] = n_polys, corners[p] = n_corners, own[p] = has_own;
    boundary_fans[p] = n_boundary, skipped_fans[p] = n_skipped, nonmanifold[p] = n_fans > 1;
  }
};

// Pass 2, per point: its polygons from its first polygon, corner and own
// point (the scans of pass 1).
struct WritePolygons {
  Fans fans;
  const std::uint32_t* corners;  // per sorted position
  const std::uint32_t* cell_of;
  const Id* first_poly;
  const Id* first_corner;
  const Id* first_own;
  Id cells;
  std::uint64_t* offsets_out;
  PointIndex* conn_out;
  KEYMESH_HD void operator()(Id p) const {
    Id poly = first_poly[p], at = first_corner[p];
    const auto own_point = static_cast<PointIndex>(cells + first_own[p]);
    const Id b = fans.first[p];
    fans.walk(p, [&](const std::uint32_t* fan, Id size, bool open) {
      if (!dual_kernels::fan_is_polygon(size, open)) return;
      offsets_out[poly++] = static_cast<std::uint64_t>(at);
      for (Id i = 0; i < size; ++i) conn_out[at++] = cell_of[corners[b + fan[i]]];
      if (open) conn_out[at++] = own_point;
    });
  }
};

// Cell c's centroid tuple of a point field (or the positions).
struct Centroids {
  const PointIndex* conn;
  Cells cells;
  const float* values;
  int components;
  bool renormalise;
  float* out;
  KEYMESH_HD void operator()(Id c) const {
    dual_kernels::centroid_tuple(conn, cells.begin(c), cells.end(c), values, components, renormalise,
                                 out + c * components);
  }
};

// A point with an open fan copied after the centroids (its tuple of a field).
struct OwnPoints {
  const Id* own;
  const Id* first_own;
  Id cells;
  const float* values;
  int components;
  float* out;
  KEYMESH_HD void operator()(Id p) const {
    if (!own[p]) return;
    const Id q = cells + first_own[p];
    for (int x = 0; x < components; ++x) out[q * components + x] = values[p * components + x];
  }
};

// The per-point results of pass 1, scanned in place into first indices.
template <class D>
struct FanCounts {
  typename D::template Array<Id> polys, corners, own, first_own, boundary, skipped, nonmanifold;
  Id total_polys = 0, total_corners = 0, extra = 0;
  DualStats stats;
};

template <class D>
FanCounts<D> count_fans(const D& d, const Fans& fans, Id V) {
  FanCounts<D> fc;
  for (auto* a : {&fc.polys, &fc.corners, &fc.own, &fc.first_own, &fc.boundary, &fc.skipped, &fc.nonmanifold})
    *a = d.template allocate<Id>(V + 1);
  d.for_each(V, CountFans{fans, fc.polys.data(), fc.corners.data(), fc.own.data(), fc.boundary.data(),
                          fc.skipped.data(), fc.nonmanifold.data()});
  fc.total_polys = d.exclusive_scan(fc.polys.data(), fc.polys.data(), V);
  fc.total_corners = d.exclusive_scan(fc.corners.data(), fc.corners.data(), V);
  fc.extra = d.exclusive_scan(fc.own.data(), fc.first_own.data(), V);
  fc.stats.polygons = fc.total_polys;
  fc.stats.boundary_fans = d.exclusive_scan(fc.boundary.data(), fc.boundary.data(), V);
  fc.stats.skipped_fans = d.exclusive_scan(fc.skipped.data(), fc.skipped.data(), V);
  fc.stats.nonmanifold_points = d.exclusive_scan(fc.nonmanifold.data(), fc.nonmanifold.data(), V);
  return fc;
}

// The dual's points and point fields: centroids, then own points.
template <class D>
void write_points(const D& d, const SurfaceMesh& m, const PointIndex* conn, Cells cells, const FanCounts<D>& fc,
                  SurfaceMesh& out) {
  const Id V = m.num_points(), F = m.num_cells(), n = F + fc.extra;
  auto tuples = [&](const Array<float>& in, int k, bool renormalise) {
    typename D::template Array<float> holder;
    const float* values = device::readable(d, in.data(), static_cast<Id>(in.size()), holder);
    auto a = d.template allocate_output<float>(k * n);
    d.for_each(F, Centroids{conn, cells, values, k, renormalise, a.data()});
    d.for_each(V, OwnPoints{fc.own.data(), fc.first_own.data(), F, values, k, a.data()});
    return d.to_host(std::move(a));
  };
  out.points = tuples(m.points, 3, false);
  for (const Field& f : m.point_fields)
    out.point_fields.push_back({f.name, f.components, tuples(f.values, f.components,
                                                             f.name == "Normals" && f.components == 3)});
}

}  // namespace device_dual

// The device path on device `d`: dual()'s checks and output, statistics
// included.
template <class D>
SurfaceMesh dual_on(const D& d, const SurfaceMesh& m, DualStats* stats = nullptr) {
  using namespace device_dual;
  analyze::check_ids(m);
  const Id V = m.num_points(), F = m.num_cells(), n = static_cast<Id>(m.connectivity.size());
  typename D::template Array<PointIndex> conn_holder;
  typename D::template Array<std::uint64_t> offsets_holder;
  const PointIndex* conn = device::readable(d, m.connectivity.data(), n, conn_holder);
  const Cells cells{m.offsets.empty() ? nullptr
                                      : device::readable(d, m.offsets.data(), static_cast<Id>(m.offsets.size()),
                                                         offsets_holder)};
  auto cell_of = d.template allocate<std::uint32_t>(n);
  d.for_each(F, CellOfCorner{cells, cell_of.data()});
  // The incidence: corners grouped by point, each point's in increasing order.
  auto keys = d.template allocate<PointIndex>(n);
  device::copy(d, conn, n, keys.data());
  const auto g = device::group_keys(d, keys.data(), n,
                                    parallel::bits_needed(static_cast<std::uint32_t>(V > 0 ? V - 1 : 0)));
  auto first = d.template allocate<Id>(V + 1);
  device::fill(d, first.data(), V + 1, Id{0});
  d.for_each(g.groups, CornerCounts{g.unique_keys.data(), g.offsets.data(), first.data()});
  d.exclusive_scan(first.data(), first.data(), V + 1);
  auto next = d.template allocate<PointIndex>(n), prev = d.template allocate<PointIndex>(n);
  d.for_each(n, Links{conn, cells, g.sorted_pairs.data(), cell_of.data(), next.data(), prev.data()});
  auto used = d.template allocate<std::uint8_t>(n);
  auto order = d.template allocate<std::uint32_t>(n);
  const Fans fans{first.data(), next.data(), prev.data(), used.data(), order.data()};
  FanCounts<D> fc = count_fans(d, fans, V);
  if (F + fc.extra > Id{UINT32_MAX} || fc.total_corners > Id{UINT32_MAX})
    throw LimitError("dual: " + std::to_string(F + fc.extra) + " points or " + std::to_string(fc.total_corners) +
                     " corners exceed 2^32 - 1");
  SurfaceMesh out;
  write_points(d, m, conn, cells, fc, out);
  auto offsets_out = d.template allocate_output<std::uint64_t>(fc.total_polys + 1);
  auto conn_out = d.template allocate_output<PointIndex>(fc.total_corners);
  d.for_each(1, device::functors::SetOne<std::uint64_t>{offsets_out.data() + fc.total_polys,
                                                       static_cast<std::uint64_t>(fc.total_corners)});
  d.for_each(V, WritePolygons{fans, g.sorted_pairs.data(), cell_of.data(), fc.polys.data(), fc.corners.data(),
                              fc.first_own.data(), F, offsets_out.data(), conn_out.data()});
  out.connectivity = d.to_host(std::move(conn_out));
  out.offsets = d.to_host(std::move(offsets_out));
  if (stats) *stats = fc.stats;
  return out;
}

}  // namespace keymesh::generate
