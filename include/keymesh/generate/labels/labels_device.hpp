#pragma once
// Label surface nets, the network (labels.hpp), over the device layer
// (keymesh/device/), written once for every device:
//   the label volume scanned on the host (distinct labels, the padded
//   index volume: scan_labels_for_device) and uploaded ->
//   map: per row of padded points, how many of their edges join two labels
//   -> exclusive scan (64-bit) -> each such edge's quad, 4 cell keys as two
//   triangles, and its label pair (label_kernels::network_quad, the CPU
//   path's) ->
//   weld: KEY-REDUCE's grouping (stable radix sort + run-length: points in
//   cell order, the index map is the triangle list) -> every point from its
//   cell (centre, junction, border axes: label_kernels) ->
//   smoothing: the directed quad sides as (from, to) keys, sorted and made
//   unique (each point's neighbours in increasing order), junctions keeping
//   their junction neighbours; then per iteration a Jacobi step and the
//   fold guard, one for_each each (label_kernels::SmoothStep and GuardStep,
//   the CPU path's) ->
//   boundary_labels from each triangle's pair.
// Equal to contour_labels() bit for bit for the network, with any
// smoothing, label selection and background (ctest runs it on the CPU
// device: tests/generate/labels/labels_device_test.cpp). Refused by name
// (InputError): --method discrete-mc, --per-label, --coarsen. The scan stays
// on the host: its table of distinct values is small, the index volume
// 2 bytes a voxel.
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/device.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/device/algorithms.hpp"
#include "keymesh/device/key_groups.hpp"
#include "keymesh/generate/labels/label_kernels.hpp"
#include "keymesh/generate/labels/labels.hpp"
#include "keymesh/parallel/bits_needed.hpp"

namespace keymesh::generate {

// The options the device path lacks, refused by name.
void check_device_label_options(const LabelOptions& options);

// What the device path reads of contour_labels()'s scan of the volume (its
// checks included): the padded label-index volume (x fastest), where its
// points lie, and every label index's value as boundary_labels stores it.
struct ScannedLabels {
  label_kernels::Placement place;
  std::vector<std::uint16_t> index;
  std::vector<float> value_of;
  Id distinct_labels = 0, surfaces = 0;  // LabelStats'
  double seconds = 0;                    // the scan's, on the host's clock
};
ScannedLabels scan_labels_for_device(const ImageGrid& grid, const LabelOptions& options);

// contour_labels() through the device path on the CPU device;
// `force_64bit_keys` welds with 64-bit cell keys where 32 bits would do
// (what a volume of more than 2^32 cells needs; tests use it).
SurfaceMesh contour_labels_on_cpu_device(const ImageGrid& grid, const LabelOptions& options,
                                         LabelStats* stats = nullptr, bool force_64bit_keys = false);

}  // namespace keymesh::generate

namespace keymesh::generate::device_labels {

// The padded index volume as the kernels read it.
struct Volume {
  const std::uint16_t* index;
  Id dims[3];
  KEYMESH_HD Id nxy() const { return dims[0] * dims[1]; }
  // The labels at the far ends of point p's edges along +x, +y, +z (p's own
  // label where the grid ends: no edge); returns p's label.
  KEYMESH_HD std::uint16_t ends(Id p, Id g[3], std::uint16_t end[3]) const {
    g[0] = p % dims[0], g[1] = (p / dims[0]) % dims[1], g[2] = p / nxy();
    const std::uint16_t a = index[p];
    end[0] = g[0] + 1 < dims[0] ? index[p + 1] : a;
    end[1] = g[1] + 1 < dims[1] ? index[p + dims[0]] : a;
    end[2] = g[2] + 1 < dims[2] ? index[p + nxy()] : a;
    return a;
  }
};

// Per row of padded points (y fastest, then z; point i of row r is
// r * dims[0] + i): the quads of its points' edges whose two labels differ.
// A thread per row, as the CPU path counts: no per-point counts or offsets
// (8 bytes a voxel) held.
struct EdgeCounts {
  Volume vol;
  Id* counts;
  KEYMESH_HD void operator()(Id r) const {
    Id n = 0, g[3];
    std::uint16_t end[3];
    for (Id p = r * vol.dims[0]; p < (r + 1) * vol.dims[0]; ++p) {
      const std::uint16_t a = vol.ends(p, g, end);
      n += (end[0] != a) + (end[1] != a) + (end[2] != a);
    }
    counts[r] = n;
  }
};

// Per row, from its first quad: the quads' keys (6 each) and the label pair
// of their two triangles, in grid order then axis order (the CPU path's
// soup).
template <class K>
struct WriteQuads {
  Volume vol;
  const Id* first_quad;
  K* keys;
  std::uint32_t* pair;
  KEYMESH_HD void operator()(Id r) const {
    const Id cx = vol.dims[0] - 1;
    const Id cstride[3] = {1, cx, cx * (vol.dims[1] - 1)};
    Id t = 2 * first_quad[r], g[3];
    std::uint16_t end[3];
    for (Id p = r * vol.dims[0]; p < (r + 1) * vol.dims[0]; ++p) {
      const std::uint16_t a = vol.ends(p, g, end);
      const Id cell = g[0] + g[1] * cstride[1] + g[2] * cstride[2];
      for (int axis = 0; axis < 3; ++axis) {
        const std::uint16_t b = end[axis];
        if (a == b) continue;
        label_kernels::network_quad(cell, cstride, axis, a < b, keys + 3 * t);
        const std::uint16_t lo = a < b ? a : b, hi = a < b ? b : a;
        pair[t] = pair[t + 1] = (std::uint32_t{lo} << 16) | hi;
        t += 2;
      }
    }
  }
};

// Point q from its cell key: the cell's centre, its border axes and
// whether three labels or more meet in the cell.
template <class K>
struct CellPoints {
  Volume vol;
  label_kernels::Placement place;
  const K* cell_keys;
  float* points;
  float* centre;
  std::uint8_t* border_axes;
  std::uint8_t* junction;
  KEYMESH_HD void operator()(Id q) const {
    const auto cell = static_cast<Id>(cell_keys[q]);
    const Id cx = vol.dims[0] - 1, cy = vol.dims[1] - 1;
    const Id g[3] = {cell % cx, (cell / cx) % cy, cell / (cx * cy)};
    const double offset[3] = {0, 0, 0};
    border_axes[q] = place.cell_point(g, offset, points + 3 * q, centre + 3 * q);
    const Id first = g[0] + g[1] * vol.dims[0] + g[2] * vol.nxy();
    const Id nx = vol.dims[0], nxy = vol.nxy();
    const std::uint16_t* index = vol.index;
    junction[q] = label_kernels::distinct_corner_labels([&](int c) {
                    return index[first + (c & 1) + ((c >> 1) & 1) * nx + ((c >> 2) & 1) * nxy];
                  }) >= 3;
  }
};

// Quad q's four sides (C00 C10, C10 C11, C11 C01, C01 C00: corners 0-1, 1-2,
// 4-5, 5-3 of its two triangles), both ways, as from << 32 | to.
struct QuadSides {
  const PointIndex* conn;
  std::uint64_t* keys;
  KEYMESH_HD void operator()(Id q) const {
    constexpr int kSides[4][2] = {{0, 1}, {1, 2}, {4, 5}, {5, 3}};
    const PointIndex* c = conn + 6 * q;
    for (int k = 0; k < 4; ++k) {
      const std::uint64_t a = c[kSides[k][0]], b = c[kSides[k][1]];
      keys[8 * q + 2 * k] = a << 32 | b;
      keys[8 * q + 2 * k + 1] = b << 32 | a;
    }
  }
};

// From the sorted distinct sides: each point's span [begin, end) of them
// (points without sides keep an empty span).
struct SideSpans {
  const std::uint64_t* sides;
  Id count;
  Id* begin;
  Id* end;
  KEYMESH_HD void operator()(Id e) const {
    const std::uint64_t from = sides[e] >> 32;
    if (e == 0 || sides[e - 1] >> 32 != from) begin[from] = e;
    if (e + 1 == count || sides[e + 1] >> 32 != from) end[from] = e + 1;
  }
};

// A point's stencil: its neighbours in increasing order; a junction keeps
// only its junction neighbours, and none unless two or more. count: their
// number; write: them, from offsets[p].
struct Stencil {
  const std::uint64_t* sides;
  const Id* begin;
  const Id* end;
  const std::uint8_t* junction;
  KEYMESH_HD bool kept(Id p, Id j) const { return !junction[p] || junction[sides[j] & 0xffffffffu]; }
  KEYMESH_HD Id count(Id p) const {
    Id n = 0;
    for (Id j = begin[p]; j < end[p]; ++j) n += kept(p, j);
    return junction[p] && n < 2 ? 0 : n;
  }
};

struct StencilCounts {
  Stencil s;
  Id* counts;
  KEYMESH_HD void operator()(Id p) const { counts[p] = s.count(p); }
};

struct StencilWrite {
  Stencil s;
  const Id* offsets;
  std::uint32_t* neighbours;
  KEYMESH_HD void operator()(Id p) const {
    Id at = offsets[p];
    if (offsets[p + 1] == at) return;
    for (Id j = s.begin[p]; j < s.end[p]; ++j)
      if (s.kept(p, j)) neighbours[at++] = static_cast<std::uint32_t>(s.sides[j] & 0xffffffffu);
  }
};

template <class From, class To>
struct Convert {
  const From* in;
  To* out;
  KEYMESH_HD void operator()(Id i) const { out[i] = static_cast<To>(in[i]); }
};

// boundary_labels of triangle t: its pair's two label values.
struct PairValues {
  const std::uint32_t* pair;
  const float* value_of;  // per label index
  float* out;
  KEYMESH_HD void operator()(Id t) const {
    out[2 * t] = value_of[pair[t] >> 16];
    out[2 * t + 1] = value_of[pair[t] & 0xffffu];
  }
};

// The welded network on the device, before smoothing.
template <class D>
struct Surface {
  typename D::template Array<float> points, centre;
  typename D::template Array<std::uint8_t> border_axes, junction;
  typename D::template Array<std::uint32_t> connectivity, pair;
  Id points_count = 0, triangles = 0;
};

// The map step and the weld over cell keys K (32 bits where the padded
// grid's cells allow).
template <class D, class K>
Surface<D> network(const D& d, const ScannedLabels& sc, const Volume& vol, LabelStats& st) {
  Surface<D> s;
  auto mark = d.begin_stage(&st.generate);
  const Id rows = vol.dims[1] * vol.dims[2];
  auto first_quad = d.template allocate<Id>(rows);
  d.for_each(rows, EdgeCounts{vol, first_quad.data()});
  const Id quads = d.exclusive_scan(first_quad.data(), first_quad.data(), rows);
  s.triangles = 2 * quads;
  if (3 * s.triangles > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("labels: " + std::to_string(s.triangles) + " triangles exceed the supported 1431655765");
  auto keys = d.template allocate<K>(3 * s.triangles);
  s.pair = d.template allocate<std::uint32_t>(s.triangles);
  d.for_each(rows, WriteQuads<K>{vol, first_quad.data(), keys.data(), s.pair.data()});
  d.end_stage(mark);
  st.soup_corners += 3 * s.triangles;
  mark = d.begin_stage(&st.weld);
  const Id cells = (vol.dims[0] - 1) * (vol.dims[1] - 1) * (vol.dims[2] - 1);
  device::KeyGroups<D, K> g =
      device::group_keys(d, keys.data(), 3 * s.triangles, parallel::bits_needed(static_cast<K>(cells)));
  s.connectivity = std::move(g.index_map);
  s.points_count = g.groups;
  s.points = d.template allocate_output<float>(3 * g.groups);
  s.centre = d.template allocate<float>(3 * g.groups);
  s.border_axes = d.template allocate<std::uint8_t>(g.groups);
  s.junction = d.template allocate<std::uint8_t>(g.groups);
  d.for_each(g.groups, CellPoints<K>{vol, sc.place, g.unique_keys.data(), s.points.data(), s.centre.data(),
                                     s.border_axes.data(), s.junction.data()});
  d.end_stage(mark);
  return s;
}

// Every point's stencil (label_smoothing.cpp's): offsets (points + 1) into
// the neighbours.
template <class D>
struct Stencils {
  typename D::template Array<Id> offsets;
  typename D::template Array<std::uint32_t> neighbours;
};

template <class D>
Stencils<D> stencils(const D& d, const Surface<D>& s) {
  const Id P = s.points_count, quads = s.triangles / 2, n = 8 * quads;
  auto sides = d.template allocate<std::uint64_t>(n);
  d.for_each(quads, QuadSides{s.connectivity.data(), sides.data()});
  auto order = d.template allocate<std::uint32_t>(n);  // sort_pairs' values, unused
  device::iota(d, order.data(), n);
  d.sort_pairs(sides.data(), order.data(), n, 32 + parallel::bits_needed(static_cast<std::uint32_t>(P - 1)));
  const device::Runs<D, std::uint64_t> distinct = device::run_length(d, sides.data(), n);
  auto begin = d.template allocate<Id>(P), end = d.template allocate<Id>(P);
  device::fill(d, begin.data(), P, Id{0});
  device::fill(d, end.data(), P, Id{0});
  d.for_each(distinct.count, SideSpans{distinct.unique_keys.data(), distinct.count, begin.data(), end.data()});
  const Stencil stencil{distinct.unique_keys.data(), begin.data(), end.data(), s.junction.data()};
  Stencils<D> st{d.template allocate<Id>(P + 1), {}};
  d.for_each(P, StencilCounts{stencil, st.offsets.data()});
  device::fill(d, st.offsets.data() + P, 1, Id{0});
  const Id total = d.exclusive_scan(st.offsets.data(), st.offsets.data(), P + 1);
  st.neighbours = d.template allocate<std::uint32_t>(total);
  d.for_each(P, StencilWrite{stencil, st.offsets.data(), st.neighbours.data()});
  return st;
}

// The fold guard's inputs (label_fold_guard.cpp's): each triangle's frame,
// each point's corners (the connectivity's positions grouped by point by a
// stable radix sort; every point has corners, so run p is point p's) and
// its count of shortened moves.
template <class D>
struct Guard {
  typename D::template Array<double> normal, least;
  typename D::template Array<Id> offsets;
  typename D::template Array<std::uint32_t> point_corners, shortened;
};

template <class D>
Guard<D> guard(const D& d, const Surface<D>& s) {
  const Id P = s.points_count, T = s.triangles, n = 3 * T;
  Guard<D> g{d.template allocate<double>(3 * T), d.template allocate<double>(T), {},
             d.template allocate<std::uint32_t>(n), d.template allocate<std::uint32_t>(P)};
  d.for_each(T, label_kernels::GuardFrame{s.points.data(), s.connectivity.data(), s.junction.data(), g.normal.data(),
                                          g.least.data()});
  auto keys = d.template allocate<std::uint32_t>(n);
  device::copy(d, s.connectivity.data(), n, keys.data());
  device::iota(d, g.point_corners.data(), n);
  d.sort_pairs(keys.data(), g.point_corners.data(), n, parallel::bits_needed(static_cast<std::uint32_t>(P - 1)));
  g.offsets = device::run_length(d, keys.data(), n).offsets;
  device::fill(d, g.shortened.data(), P, std::uint32_t{0});
  return g;
}

// Surface nets' smoothing (Laplacian steps clamped to the cell, each
// iteration's moves limited by the fold guard), in double as the CPU path
// does; st.guard_shortened counts the moves the guard shortened or refused.
template <class D>
void smooth(const D& d, Surface<D>& s, const ScannedLabels& sc, const LabelOptions& options, LabelStats& st) {
  const Id P = s.points_count;
  if (options.smooth_iterations <= 0 || P == 0) return;
  const Stencils<D> stencil = stencils(d, s);
  Guard<D> g = guard(d, s);
  auto x = d.template allocate<double>(3 * P), candidate = d.template allocate<double>(3 * P),
       next = d.template allocate<double>(3 * P);
  d.for_each(3 * P, Convert<float, double>{s.points.data(), x.data()});
  label_kernels::SmoothStep step{stencil.offsets.data(), stencil.neighbours.data(), s.border_axes.data(),
                                 s.centre.data(), {0.5 * sc.place.spacing[0], 0.5 * sc.place.spacing[1],
                                 0.5 * sc.place.spacing[2]}, true, options.relaxation, nullptr, candidate.data()};
  label_kernels::GuardStep limit{s.connectivity.data(), g.offsets.data(), g.point_corners.data(), g.normal.data(),
                                 g.least.data(), nullptr, candidate.data(), nullptr, g.shortened.data()};
  for (int it = 0; it < options.smooth_iterations; ++it) {
    step.x = x.data();
    d.for_each(P, step);
    limit.x = x.data(), limit.out = next.data();
    d.for_each(P, limit);
    std::swap(x, next);
  }
  d.for_each(3 * P, Convert<double, float>{x.data(), s.points.data()});
  auto total = d.template allocate<Id>(P);
  st.guard_shortened = d.exclusive_scan(g.shortened.data(), total.data(), P);
}

// The mesh contour_labels returns: points, triangles, boundary_labels.
template <class D>
SurfaceMesh to_mesh(const D& d, Surface<D>&& s, const ScannedLabels& sc) {
  typename D::template Array<float> values_holder;
  const float* values =
      device::readable(d, sc.value_of.data(), static_cast<Id>(sc.value_of.size()), values_holder);
  auto pairs = d.template allocate_output<float>(2 * s.triangles);
  d.for_each(s.triangles, PairValues{s.pair.data(), values, pairs.data()});
  SurfaceMesh mesh;
  mesh.points = d.to_host(std::move(s.points));
  mesh.connectivity = d.to_host(std::move(s.connectivity));
  mesh.cell_fields.push_back(Field{"boundary_labels", 2, d.to_host(std::move(pairs))});
  return mesh;
}

}  // namespace keymesh::generate::device_labels

namespace keymesh::generate {

// The device path on device `d`: contour_labels()'s checks, those of the
// options this path lacks, then the scan on the host and the rest on `d`.
template <class D>
SurfaceMesh contour_labels_on(const D& d, const ImageGrid& grid, const LabelOptions& options, LabelStats* stats,
                              bool force_64bit_keys = false) {
  using namespace device_labels;
  check_device_label_options(options);
  LabelStats local;
  LabelStats& st = stats ? *stats : local;
  st = LabelStats{};
  const ScannedLabels sc = scan_labels_for_device(grid, options);
  st.scan = sc.seconds;
  st.distinct_labels = sc.distinct_labels;
  st.surfaces = sc.surfaces;
  auto mark = d.begin_stage(&st.generate);  // the upload
  typename D::template Array<std::uint16_t> index_holder;
  const Volume vol{device::readable(d, sc.index.data(), static_cast<Id>(sc.index.size()), index_holder),
                   {sc.place.dims[0], sc.place.dims[1], sc.place.dims[2]}};
  d.end_stage(mark);
  const Id cells = (vol.dims[0] - 1) * (vol.dims[1] - 1) * (vol.dims[2] - 1);
  Surface<D> s = !force_64bit_keys && cells <= Id{std::numeric_limits<std::uint32_t>::max()}
                     ? network<D, std::uint32_t>(d, sc, vol, st)
                     : network<D, std::uint64_t>(d, sc, vol, st);
  mark = d.begin_stage(&st.smooth);
  smooth(d, s, sc, options, st);
  d.end_stage(mark);
  return to_mesh(d, std::move(s), sc);
}

}  // namespace keymesh::generate
