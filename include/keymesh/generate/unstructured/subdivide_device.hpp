#pragma once
// Uniform subdivision (subdivide.hpp) over the device layer (keymesh/device/),
// written once for every device:
//   an edge key per cell edge -> KEY-REDUCE's grouping (stable radix sort +
//   run-length: new points in key order, the index map) -> every new point
//   from its key (subdivide_kernels.hpp, the CPU path's arithmetic) -> the
//   children of every cell from the index map (triangles 1 -> 4, tets 1 -> 8).
// A surface stays on the device from level to level; a tet grid goes back
// to the host between levels (its id width may grow). Equal to subdivide()
// bit for bit (ctest runs it on the CPU device:
// tests/generate/unstructured/subdivide_device_test.cpp). KeyReduce only
// (VERTEX-WELD, the baseline, is refused by name).
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/device.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/device/algorithms.hpp"
#include "keymesh/device/key_groups.hpp"
#include "keymesh/generate/device_surface.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"
#include "keymesh/generate/unstructured/subdivide_kernels.hpp"
#include "keymesh/mesh/fields.hpp"
#include "keymesh/mesh/keys.hpp"
#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/mesh/cell_tables.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::generate {

// subdivide() through the device path on the CPU device (triangles, tets).
SurfaceMesh subdivide_on_cpu_device(const SurfaceMesh& mesh, const SubdivideOptions& options);
UnstructuredGrid subdivide_on_cpu_device(const UnstructuredGrid& tets, const SubdivideOptions& options);

namespace device_subdivide {

struct SideKeys {
  const PointIndex* triangles;
  EdgeKeys ek;
  std::uint64_t* keys;
  KEYMESH_HD void operator()(Id t) const {
    for (int e = 0; e < 3; ++e) keys[3 * t + e] = ek(triangles[3 * t + e], triangles[3 * t + (e + 1) % 3]);
  }
};

// Position (and with Bezier, normal) of new point e, after the V old ones.
struct EdgePoints {
  const std::uint64_t* edge_key;
  EdgeKeys ek;
  Id old_points;
  const float* points_in;
  const float* normals_in;  // Bezier: the "Normals" field; null: linear
  float* points_out;
  float* normals_out;  // Bezier: the new points' normals; null otherwise
  KEYMESH_HD void operator()(Id e) const {
    const auto ab = ek.decode(edge_key[e]);
    const Id a = static_cast<Id>(ab.first), b = static_cast<Id>(ab.second);
    subdivision::edge_point(points_in + 3 * a, points_in + 3 * b, normals_in ? normals_in + 3 * a : nullptr,
                            normals_in ? normals_in + 3 * b : nullptr, points_out + 3 * (old_points + e),
                            normals_out ? normals_out + 3 * (old_points + e) : nullptr);
  }
};

// Tuple of new point e (`components` of them) from its edge's two
// (subdivision::midpoint_tuple; `renormalize` for a normals field): the
// surfaces' point fields and the tets'.
struct EdgeTuples {
  const std::uint64_t* edge_key;
  EdgeKeys ek;
  Id old_points;
  int components;
  bool renormalize;
  const float* in;
  float* out;
  KEYMESH_HD void operator()(Id e) const {
    const auto ab = ek.decode(edge_key[e]);
    const Id a = static_cast<Id>(ab.first), b = static_cast<Id>(ab.second);
    subdivision::midpoint_tuple(in + components * a, in + components * b, components, renormalize,
                                out + components * (old_points + e));
  }
};

// The four children of triangle t: a corner triangle at each corner, then
// the middle one (subdivide()'s order).
struct Children {
  const PointIndex* in;
  const std::uint32_t* index_map;
  Id old_points;
  PointIndex* out;
  KEYMESH_HD void operator()(Id t) const {
    const PointIndex a = in[3 * t], b = in[3 * t + 1], c = in[3 * t + 2];
    const auto ab = static_cast<PointIndex>(old_points + index_map[3 * t]);
    const auto bc = static_cast<PointIndex>(old_points + index_map[3 * t + 1]);
    const auto ca = static_cast<PointIndex>(old_points + index_map[3 * t + 2]);
    const PointIndex tri[12] = {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca};
    for (int i = 0; i < 12; ++i) out[12 * t + i] = tri[i];
  }
};

// Every cell's tuple repeated for its `children` cells.
struct RepeatTuples {
  const float* in;
  int components;
  int children;
  float* out;
  KEYMESH_HD void operator()(Id i) const {
    const Id tuple = i / components, c = i % components;
    out[i] = in[(tuple / children) * components + c];
  }
};

// A triangle mesh in device memory (device_surface.hpp, shared with coarsening).
template <class D>
using Field = device_surface::Field<D>;
template <class D>
using Surface = device_surface::Surface<D>;
using device_surface::download;
using device_surface::upload;

// The first field named "Normals" when it has 3 components, or -1
// (SurfaceMesh::find_point_field's choice).
template <class D>
int normals_of(const Surface<D>& s) {
  for (std::size_t i = 0; i < s.point_fields.size(); ++i)
    if (s.point_fields[i].name == "Normals") return s.point_fields[i].components == 3 ? static_cast<int>(i) : -1;
  return -1;
}

// The old points' tuples, then the new points' from their edges.
template <class D>
typename D::template Array<float> extended(const D& d, const typename D::template Array<float>& in, int components,
                                           Id old_points, Id new_points) {
  auto out = d.template allocate<float>(components * (old_points + new_points));
  device::copy(d, in.data(), components * old_points, out.data());
  return out;
}

template <class D>
Surface<D> subdivide_once(const D& d, const Surface<D>& m, SubdivideScheme scheme) {
  const Id V = m.points_count, F = m.triangle_count;
  const EdgeKeys ek = EdgeKeys::for_points(V, "subdivide");
  const int normals = normals_of(m);
  const bool bezier = scheme == SubdivideScheme::Bezier;
  if (bezier && normals < 0)
    throw InputError("subdivide --scheme bezier needs point normals (a 3-component \"Normals\" field; "
                     "contour with --normals average or gradient)");
  auto keys = d.template allocate<std::uint64_t>(3 * F);
  d.for_each(F, SideKeys{m.triangles.data(), ek, keys.data()});
  device::KeyGroups<D, std::uint64_t> g = device::group_keys(d, keys.data(), 3 * F, ek.key_bits());
  const Id E = g.groups;
  if (V + E > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("subdivide: the surface would have " + std::to_string(V + E) + " points (more than 2^32 - 1)");
  Surface<D> out{extended(d, m.points, 3, V, E), d.template allocate<PointIndex>(12 * F), {}, {}, V + E, 4 * F};
  for (std::size_t i = 0; i < m.point_fields.size(); ++i) {
    const Field<D>& f = m.point_fields[i];
    out.point_fields.push_back({f.name, f.components, extended(d, f.values, f.components, V, E)});
    const bool is_normals = static_cast<int>(i) == normals;
    if (is_normals && bezier) continue;  // set with the position
    d.for_each(E, EdgeTuples{g.unique_keys.data(), ek, V, f.components, is_normals, f.values.data(),
                             out.point_fields.back().values.data()});
  }
  const float* normals_in = bezier ? m.point_fields[normals].values.data() : nullptr;
  float* normals_out = bezier ? out.point_fields[normals].values.data() : nullptr;
  d.for_each(E, EdgePoints{g.unique_keys.data(), ek, V, m.points.data(), normals_in, out.points.data(), normals_out});
  d.for_each(F, Children{m.triangles.data(), g.index_map.data(), V, out.triangles.data()});
  for (const Field<D>& f : m.cell_fields) {
    out.cell_fields.push_back({f.name, f.components, d.template allocate<float>(4 * F * f.components)});
    d.for_each(4 * F * f.components, RepeatTuples{f.values.data(), f.components, 4, out.cell_fields.back().values.data()});
  }
  return out;
}

// Tets: the key of every edge of tet t.
template <class I>
struct TetEdgeKeys {
  const I* conn;
  EdgeKeys ek;
  std::uint64_t* keys;
  KEYMESH_HD void operator()(Id t) const {
    for (int e = 0; e < 6; ++e)
      keys[6 * t + e] = ek(conn[4 * t + cells::kTetEdges[e][0]], conn[4 * t + cells::kTetEdges[e][1]]);
  }
};

template <class I, class O>
struct TetChildren {
  const I* conn;
  const std::uint32_t* index_map;
  Id old_points;
  const float* P;  // the output points
  O* out;
  KEYMESH_HD void operator()(Id t) const {
    std::uint64_t v[10], children[8][4];
    for (int k = 0; k < 4; ++k) v[k] = conn[4 * t + k];
    for (int e = 0; e < 6; ++e) v[4 + e] = static_cast<std::uint64_t>(old_points + index_map[6 * t + e]);
    subdivision::tet_children(v, P, children);
    for (int c = 0; c < 8; ++c)
      for (int k = 0; k < 4; ++k) out[32 * t + 4 * c + k] = static_cast<O>(children[c][k]);
  }
};

// One level of tets 1 -> 8 (the input's ids of type I).
template <class D, class I>
UnstructuredGrid subdivide_tets_once(const D& d, const UnstructuredGrid& m, const I* host_conn) {
  const Id V = m.num_points(), T = m.num_cells();
  const EdgeKeys ek = EdgeKeys::for_points(V, "subdivide");
  typename D::template Array<I> conn_copy;
  const I* conn = device::readable(d, host_conn, 4 * T, conn_copy);
  auto keys = d.template allocate<std::uint64_t>(6 * T);
  d.for_each(T, TetEdgeKeys<I>{conn, ek, keys.data()});
  device::KeyGroups<D, std::uint64_t> g = device::group_keys(d, keys.data(), 6 * T, ek.key_bits());
  const Id E = g.groups;
  if (V + E > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("subdivide: the grid would have " + std::to_string(V + E) + " points (more than 2^32 - 1)");
  auto grown = [&](const Array<float>& in, int k) {
    typename D::template Array<float> holder;
    const float* values = device::readable(d, in.data(), static_cast<Id>(in.size()), holder);
    auto out = d.template allocate<float>(k * (V + E));
    device::copy(d, values, k * V, out.data());
    d.for_each(E, EdgeTuples{g.unique_keys.data(), ek, V, k, false, values, out.data()});
    return out;
  };
  auto points = grown(m.points, 3);
  UnstructuredGrid out;
  out.uniform_type = CellType::Tetra;
  for (const keymesh::Field& f : m.point_fields)
    out.point_fields.push_back({f.name, f.components, d.to_host(grown(f.values, f.components))});
  out.connectivity = IndexArray::for_ids(static_cast<std::uint64_t>(V + E), 0);
  auto children = [&](auto type) {
    using O = decltype(type);
    auto ids = d.template allocate<O>(32 * T);
    d.for_each(T, TetChildren<I, O>{conn, g.index_map.data(), V, points.data(), ids.data()});
    return d.to_host(std::move(ids));
  };
  if (out.connectivity.wide()) out.connectivity.wide_values() = children(std::uint64_t{});
  else out.connectivity.narrow() = children(std::uint32_t{});
  out.points = d.to_host(std::move(points));
  out.cell_fields = repeat_cell_fields(m.cell_fields, T, 8);
  return out;
}

// subdivide()'s input checks (a surface or tets), then the refusal of what
// the device path lacks: VERTEX-WELD.
template <class Mesh>
void check_input(const Mesh& mesh, const SubdivideOptions& options) {
  check_subdivide_input(mesh, options);
  if (options.weld != SubdivideWeld::KeyReduce)
    throw InputError("subdivide: VERTEX-WELD (--weld vertexweld) is not available on the device path (use --backend cpu)");
}

}  // namespace device_subdivide

// The device path on device `d`: subdivide()'s input checks, then every
// level on the device.
template <class D>
SurfaceMesh subdivide_on(const D& d, const SurfaceMesh& mesh, const SubdivideOptions& options) {
  device_subdivide::check_input(mesh, options);
  if (options.levels == 0) return subdivided_zero_levels(mesh);
  device_subdivide::Surface<D> cur = device_subdivide::upload(d, mesh);
  for (int level = 0; level < options.levels; ++level) cur = device_subdivide::subdivide_once(d, cur, options.scheme);
  return device_subdivide::download(d, std::move(cur));
}

// Tets 1 -> 8 on device `d`: subdivide(tets)'s checks, then level after level.
template <class D>
UnstructuredGrid subdivide_on(const D& d, const UnstructuredGrid& tets, const SubdivideOptions& options) {
  device_subdivide::check_input(tets, options);
  if (options.levels == 0) return subdivided_zero_levels(tets);
  auto once = [&](const UnstructuredGrid& m) {
    if (m.connectivity.wide()) return device_subdivide::subdivide_tets_once(d, m, m.connectivity.wide_values().data());
    return device_subdivide::subdivide_tets_once(d, m, m.connectivity.narrow().data());
  };
  UnstructuredGrid cur = once(tets);
  for (int level = 1; level < options.levels; ++level) cur = once(cur);
  return cur;
}

}  // namespace keymesh::generate
