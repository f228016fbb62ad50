#pragma once
// Coarsening by key (coarsen.hpp) over the device layer (keymesh/device/),
// written once for every device:
//   KEY-REDUCE's grouping of the points by coarse key (stable radix sort +
//   run-length: coarse points in key order, a group's points in index order,
//   the index map) -> every position and point field the mean of its group,
//   summed in double left to right (coarsening::group_mean, the CPU path's
//   arithmetic; "Normals" renormalised) -> the triangles through the index
//   map -> folds found by grouping the triangles by their sorted point triple
//   (three stable radix sorts, one per id; a set's triangles stay in index
//   order) and decided by remove_folds' rule -> one scan keeps the triangles
//   with three distinct points that no fold removed, with their cell tuples.
// Then ON THE HOST: the device's mesh is read back and split_nonmanifold (a
// sequential Gauss-Seidel rule over the edges, split_nonmanifold.hpp) and
// remove_points finish it, as coarsen() does. Equal to coarsen() bit for bit
// (ctest runs it on the CPU device: tests/generate/coarsen/coarsen_device_test.cpp).
//
// contour_coarsened_on is `contour --coarsen` on a device: the voxel
// contour's device path (contour_device.hpp), which writes every point's
// nearest grid point as its coarse key, then this coarsening on the device,
// the split on the host, averaged normals (when asked for) on the host
// (keymesh::average_normals, as contour() makes them after coarsening).
// Equal to contour() with coarsen on, either plan, bit for bit.
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "keymesh/core/device.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/device/algorithms.hpp"
#include "keymesh/device/key_groups.hpp"
#include "keymesh/generate/coarsen/coarsen.hpp"
#include "keymesh/generate/coarsen/coarsen_kernels.hpp"
#include "keymesh/generate/coarsen/split_nonmanifold.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/contour/contour_device.hpp"
#include "keymesh/generate/device_surface.hpp"
#include "keymesh/mesh/normals.hpp"
#include "keymesh/mesh/unused_points.hpp"

namespace keymesh::generate {

// coarsen() through the device path on the CPU device.
SurfaceMesh coarsen_on_cpu_device(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys,
                                  std::uint64_t key_range, CoarsenStats* stats = nullptr);

// contour() with options.coarsen through the device path on the CPU device.
SurfaceMesh contour_coarsened_on_cpu_device(const ImageGrid& grid, const ContourOptions& options,
                                            ContourStats* stats = nullptr, DeviceKeys keys = DeviceKeys::Narrowest);

namespace device_coarsen {

// Group g's mean of every component of a field of k components; a normals
// field made unit again.
struct GroupMeans {
  const Id* offsets;
  const std::uint32_t* order;
  const float* in;
  int k;
  bool renormalize;
  float* out;
  KEYMESH_HD void operator()(Id g) const {
    for (int c = 0; c < k; ++c) out[g * k + c] = coarsening::group_mean(in, k, c, order, offsets[g], offsets[g + 1]);
    if (renormalize) coarsening::renormalize(out + 3 * g);
  }
};

// Triangle t through the index map, its point set, and whether its three
// corners are three points (keep: 1 or 0).
struct MapTriangles {
  const PointIndex* in;
  const std::uint32_t* index_map;
  PointIndex* mapped;
  std::uint32_t *lo, *mid, *hi;
  std::int8_t* sign;
  Id* keep;
  KEYMESH_HD void operator()(Id t) const {
    for (int k = 0; k < 3; ++k) mapped[3 * t + k] = index_map[in[3 * t + k]];
    const coarsening::TriangleSet s = coarsening::triangle_set(mapped, t);
    lo[t] = s.lo, mid[t] = s.mid, hi[t] = s.hi, sign[t] = s.sign;
    keep[t] = coarsening::distinct(mapped[3 * t], mapped[3 * t + 1], mapped[3 * t + 2]) ? 1 : 0;
  }
};

// A point set as one comparable value (run_length's key).
struct Triple {
  std::uint32_t lo, mid, hi;
  KEYMESH_HD bool operator!=(const Triple& o) const { return lo != o.lo || mid != o.mid || hi != o.hi; }
};

struct TripleOf {
  const std::uint32_t *lo, *mid, *hi;
  const std::uint32_t* order;
  Triple* out;
  KEYMESH_HD void operator()(Id j) const {
    const std::uint32_t t = order[j];
    out[j] = Triple{lo[t], mid[t], hi[t]};
  }
};

// remove_folds' rule for the set of triangles over one point set (in
// increasing index): a set of one stays; otherwise, when the orientations do
// not cancel, the first triangle of the winning one stays and the others go;
// when they cancel, all go. Sets of triangles with a repeated point are
// dropped anyway.
struct DecideFolds {
  const Id* offsets;
  const std::uint32_t* order;
  const std::int8_t* sign;
  Id* keep;
  KEYMESH_HD void operator()(Id s) const {
    const Id b = offsets[s], e = offsets[s + 1];
    if (e - b == 1 || !keep[order[b]]) return;
    int net = 0;
    for (Id j = b; j < e; ++j) net += sign[order[j]];
    bool kept = false;
    for (Id j = b; j < e; ++j) {
      const bool winner = net != 0 && !kept && (sign[order[j]] > 0) == (net > 0);
      keep[order[j]] = winner ? 1 : 0;
      kept = kept || winner;
    }
  }
};

// Kept triangle t (rank: the exclusive scan of keep) at its place in the
// output, with its cell tuples (k components).
struct KeepTriangles {
  const Id* rank;
  const PointIndex* mapped;
  PointIndex* out;
  KEYMESH_HD void operator()(Id t) const {
    if (rank[t + 1] == rank[t]) return;
    for (int k = 0; k < 3; ++k) out[3 * rank[t] + k] = mapped[3 * t + k];
  }
};

struct KeepTuples {
  const Id* rank;
  const float* in;
  int k;
  float* out;
  KEYMESH_HD void operator()(Id t) const {
    if (rank[t + 1] == rank[t]) return;
    for (int c = 0; c < k; ++c) out[rank[t] * k + c] = in[t * k + c];
  }
};

// The bits the values [0, range) need.
inline int bits_for(std::uint64_t range) {
  int bits = 0;
  while (bits < 64 && range > 1 && ((range - 1) >> bits) != 0) ++bits;
  return bits;
}

// The triangles' point sets in (lo, mid, hi) order, a set's triangles in
// index order: three stable radix sorts of the triangle ids, by hi, then
// mid, then lo; returns the order.
template <class D>
typename D::template Array<std::uint32_t> by_point_set(const D& d, const std::uint32_t* lo, const std::uint32_t* mid,
                                                     const std::uint32_t* hi, Id triangles, int bits) {
  auto order = d.template allocate<std::uint32_t>(triangles);
  device::iota(d, order.data(), triangles);
  auto keys = d.template allocate<std::uint32_t>(triangles);
  for (const std::uint32_t* key : {hi, mid, lo}) {
    device::gather(d, key, order.data(), triangles, keys.data());
    d.sort_pairs(keys.data(), order.data(), triangles, bits);
  }
  return order;
}

// remove_folds' rule over the mapped triangles: keep[t] set to 0 for the
// triangles it removes.
template <class D>
void remove_folds_on(const D& d, const std::uint32_t* lo, const std::uint32_t* mid, const std::uint32_t* hi,
                     const std::int8_t* sign, Id triangles, Id points, Id* keep) {
  auto order = by_point_set(d, lo, mid, hi, triangles, bits_for(static_cast<std::uint64_t>(points)));
  auto triples = d.template allocate<Triple>(triangles);
  d.for_each(triangles, TripleOf{lo, mid, hi, order.data(), triples.data()});
  const device::Runs<D, Triple> sets = device::run_length(d, triples.data(), triangles);
  d.for_each(sets.count, DecideFolds{sets.offsets.data(), order.data(), sign, keep});
}

// The coarse points: every position and point field averaged over its group.
template <class D, class K>
device_surface::Surface<D> averaged_points(const D& d, const device_surface::Surface<D>& in,
                                           const device::KeyGroups<D, K>& g) {
  device_surface::Surface<D> out;
  out.points_count = g.groups;
  auto mean = [&](const typename D::template Array<float>& values, int k, bool renormalize) {
    auto m = d.template allocate_output<float>(g.groups * k);
    d.for_each(g.groups, GroupMeans{g.offsets.data(), g.sorted_pairs.data(), values.data(), k, renormalize, m.data()});
    return m;
  };
  out.points = mean(in.points, 3, false);
  for (const device_surface::Field<D>& f : in.point_fields)
    out.point_fields.push_back(
        {f.name, f.components, mean(f.values, f.components, f.name == "Normals" && f.components == 3)});
  return out;
}

// The triangles through the index map, less the collapsed and the folded
// ones, with their cell tuples, into `out`; returns the triangles that had
// three distinct points (before the folds).
template <class D, class K>
Id coarse_triangles(const D& d, const device_surface::Surface<D>& in, const device::KeyGroups<D, K>& g,
                    device_surface::Surface<D>& out) {
  const Id T = in.triangle_count;
  auto mapped = d.template allocate<PointIndex>(3 * T);
  auto lo = d.template allocate<std::uint32_t>(T), mid = d.template allocate<std::uint32_t>(T),
       hi = d.template allocate<std::uint32_t>(T);
  auto sign = d.template allocate<std::int8_t>(T);
  auto keep = d.template allocate<Id>(T + 1);
  device::fill(d, keep.data() + T, 1, Id{0});
  d.for_each(T, MapTriangles{in.triangles.data(), g.index_map.data(), mapped.data(), lo.data(), mid.data(), hi.data(),
                             sign.data(), keep.data()});
  auto rank = d.template allocate<Id>(T + 1);
  const Id distinct = d.exclusive_scan(keep.data(), rank.data(), T + 1);
  remove_folds_on(d, lo.data(), mid.data(), hi.data(), sign.data(), T, g.groups, keep.data());
  out.triangle_count = d.exclusive_scan(keep.data(), rank.data(), T + 1);
  out.triangles = d.template allocate_output<PointIndex>(3 * out.triangle_count);
  d.for_each(T, KeepTriangles{rank.data(), mapped.data(), out.triangles.data()});
  for (const device_surface::Field<D>& f : in.cell_fields) {
    out.cell_fields.push_back({f.name, f.components, d.template allocate_output<float>(out.triangle_count * f.components)});
    d.for_each(T, KeepTuples{rank.data(), f.values.data(), f.components, out.cell_fields.back().values.data()});
  }
  return distinct;
}

// The surface coarsened by `keys` (one per point, each < key_range, sorted
// in place): the device's part, then the split on the host.
template <class D>
SurfaceMesh coarsen_surface(const D& d, const device_surface::Surface<D>& in, std::uint64_t* keys,
                            std::uint64_t key_range, CoarsenStats* stats) {
  const Id n = in.points_count;
  device::KeyGroups<D, std::uint64_t> g = device::group_keys(d, keys, n, bits_for(key_range));
  device_surface::Surface<D> out = averaged_points(d, in, g);
  const Id distinct = coarse_triangles(d, in, g, out);
  const Id kept = out.triangle_count;
  SurfaceMesh mesh = device_surface::download(d, std::move(out));
  remove_points(mesh, split_nonmanifold(mesh).unused);  // on the host: a sequential rule
  if (stats) *stats = CoarsenStats{n, mesh.num_points(), in.triangle_count, kept, distinct - kept};
  return mesh;
}

}  // namespace device_coarsen

// The device path on device `d`: coarsen()'s input checks, the merge, the
// index map and the folds on the device, the split on the host.
template <class D>
SurfaceMesh coarsen_on(const D& d, const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys,
                       std::uint64_t key_range, CoarsenStats* stats = nullptr) {
  check_coarsen_input(mesh, keys, key_range);
  const device_surface::Surface<D> in = device_surface::upload(d, mesh);
  auto device_keys = d.upload(keys.data(), static_cast<Id>(keys.size()));
  return device_coarsen::coarsen_surface(d, in, device_keys.data(), key_range, stats);
}

// `contour --coarsen` on device `d`: the contour's device path with every
// point's nearest grid point as its key, coarsened on the device; the split
// and averaged normals on the host.
template <class D>
SurfaceMesh contour_coarsened_on(const D& d, const ImageGrid& grid, const ContourOptions& options,
                                 ContourStats* stats = nullptr, DeviceKeys keys = DeviceKeys::Narrowest) {
  if (!options.coarsen) throw InputError("contour_coarsened_on: options.coarsen is off (contour_on contours)");
  ContourStats local;
  ContourStats& st = stats ? *stats : local;
  auto fine = device_contour::checked_contour_arrays(d, grid, false, options, st, keys);
  const auto mark = d.begin_stage(&st.coarsen);
  device_surface::Surface<D> s{std::move(fine.xyz), std::move(fine.connectivity),
                               device_contour::point_fields(std::move(fine.fields), grid.name, options),
                               {}, fine.points, fine.triangles};
  st.triangles_before_coarsening = fine.triangles;
  const std::uint64_t key_range = static_cast<std::uint64_t>(grid.num_points()) * options.isovalues.size();
  SurfaceMesh mesh = device_coarsen::coarsen_surface(d, s, fine.nearest.data(), key_range, nullptr);
  if (options.normals == ContourNormals::Average) keymesh::average_normals(mesh);
  d.end_stage(mark);
  return mesh;
}

}  // namespace keymesh::generate
