#pragma once
// Marching tetrahedra on an unstructured grid (contour_tets.hpp) over the
// device layer (keymesh/device/), written once for every device:
//   inside bits per point -> case and triangle count per tet -> exclusive scan
//   (64-bit) -> an edge key per triangle corner, in tet order -> KEY-REDUCE's
//   grouping (stable radix sort + run-length) -> positions and every point
//   field once per point, from its key (tet_kernels.hpp, the CPU path's
//   arithmetic) -> averaged normals summed per point in corner order.
// Equal to contour(tets) bit for bit (ctest runs it on the CPU device:
// tests/generate/unstructured/contour_tets_device_test.cpp). Not on this path
// (refused by name): VERTEX-WELD and coarsening.
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/device.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/device/algorithms.hpp"
#include "keymesh/device/key_groups.hpp"
#include "keymesh/generate/device_normals.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/unstructured/contour_tets.hpp"
#include "keymesh/generate/unstructured/tet_kernels.hpp"
#include "keymesh/mesh/cell_tables.hpp"
#include "keymesh/mesh/face_normal.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::generate {

// contour(tets) through the device path on the CPU device.
SurfaceMesh contour_tets_on_cpu_device(const UnstructuredGrid& tets, const ContourOptions& options,
                                       ContourStats* stats = nullptr);

namespace device_tets {

struct Inside {
  const float* S;
  double iso;
  std::uint8_t* inside;
  KEYMESH_HD void operator()(Id p) const { inside[p] = static_cast<std::uint8_t>(S[p] >= iso); }
};

// A tet's case and triangle count; `bad` 1 when a corner id is out of range
// (its count 0: the caller refuses the grid).
template <class I>
struct Classify {
  const I* conn;
  Id points;
  const std::uint8_t* inside;
  const TetTable* table;
  std::uint8_t* cases;
  std::uint8_t* counts;
  std::uint8_t* bad;
  KEYMESH_HD void operator()(Id t) const {
    const I* v = conn + 4 * t;
    bool out_of_range = false;
    for (int k = 0; k < 4; ++k) out_of_range |= static_cast<std::uint64_t>(v[k]) >= static_cast<std::uint64_t>(points);
    bad[t] = out_of_range;
    const unsigned m = out_of_range ? 0u : inside[v[0]] | (inside[v[1]] << 1) | (inside[v[2]] << 2) | (inside[v[3]] << 3);
    cases[t] = static_cast<std::uint8_t>(m);
    counts[t] = table->triangles[m];
  }
};

// Tet t's corner keys at its first triangle, wound back in a left-handed tet.
template <class I>
struct Emit {
  const I* conn;
  const float* P;
  const std::uint8_t* cases;
  const std::uint64_t* first;
  const TetTable* table;
  EdgeKeys ek;
  std::uint64_t level;
  std::uint64_t* keys;
  KEYMESH_HD void operator()(Id t) const {
    const unsigned m = cases[t];
    if (m == 0 || m == 15) return;
    const I* v = conn + 4 * t;
    const bool flip = tet_volume(P + 3 * std::uint64_t(v[0]), P + 3 * std::uint64_t(v[1]),
                                 P + 3 * std::uint64_t(v[2]), P + 3 * std::uint64_t(v[3])) < 0;
    std::uint64_t* o = keys + 3 * first[t];
    for (int tri = 0; tri < table->triangles[m]; ++tri)
      for (int corner = 0; corner < 3; ++corner) {
        const int e = table->edges[m][3 * tri + (flip && corner ? 3 - corner : corner)];
        *o++ = ek.with_level(ek(v[cells::tet_edge_corner(e, 0)], v[cells::tet_edge_corner(e, 1)]), level);
      }
  }
};

struct Positions {
  TetEdgePoints ep;
  const std::uint64_t* keys;
  float* xyz;
  KEYMESH_HD void operator()(Id p) const { ep.position(keys[p], xyz + 3 * p); }
};

struct Tuples {
  TetEdgePoints ep;
  const std::uint64_t* keys;
  const float* values;
  int components;
  bool contoured;
  float* out;
  KEYMESH_HD void operator()(Id p) const { ep.tuple(keys[p], values, components, contoured, out + components * p); }
};

// A sorted position's face normal: a point's triangles in corner order.
struct FaceOfPair {
  const std::uint32_t* sorted_pairs;
  const Vec3f* face;
  KEYMESH_HD Vec3f operator()(Id j) const { return face[sorted_pairs[j] / 3]; }
};

// The grid where the device reads it.
template <class D, class I>
struct Input {
  typename D::template Array<I> conn_copy;
  typename D::template Array<float> points_copy, samples_copy;
  typename D::template Array<TetTable> table;
  typename D::template Array<double> isovalues;
  const I* conn = nullptr;
  const float* P = nullptr;
  const float* S = nullptr;
  Id tets = 0, points = 0;
};

template <class D>
struct TetScratch {
  typename D::template Array<std::uint8_t> inside, cases, counts, bad;
  typename D::template Array<std::uint64_t> first;
};

// Refuses ids out of range as contour(tets) does: the first bad corner of
// the first bad tet named.
template <class D, class I>
void refuse_bad_ids(const D& d, const Input<D, I>& in, TetScratch<D>& s) {
  if (d.exclusive_scan(s.bad.data(), s.first.data(), in.tets) == 0) return;
  std::vector<std::uint8_t> bad(static_cast<std::size_t>(in.tets));
  d.download(s.bad.data(), in.tets, bad.data());
  Id t = 0;
  while (!bad[t]) ++t;
  I v[4];
  d.download(in.conn + 4 * t, 4, v);
  for (int k = 0; k < 4; ++k)
    if (static_cast<std::uint64_t>(v[k]) >= static_cast<std::uint64_t>(in.points))
      throw InputError("contour input: point id " + std::to_string(std::uint64_t(v[k])) + " of tet " +
                       std::to_string(t) + " is out of range (" + std::to_string(in.points) + " points)");
}

template <class D, class I>
std::uint64_t count_isovalue(const D& d, const Input<D, I>& in, double iso, TetScratch<D>& s) {
  d.for_each(in.points, Inside{in.S, iso, s.inside.data()});
  d.for_each(in.tets, Classify<I>{in.conn, in.points, s.inside.data(), in.table.data(), s.cases.data(),
                                  s.counts.data(), s.bad.data()});
  refuse_bad_ids(d, in, s);
  return d.exclusive_scan(s.counts.data(), s.first.data(), in.tets);
}

// The soup of every isovalue in turn, tet order within each.
template <class D, class I>
typename D::template Array<std::uint64_t> emit_soup(const D& d, const Input<D, I>& in, const ContourOptions& opt,
                                                    const EdgeKeys& ek, Id& corners) {
  const Id n_iso = static_cast<Id>(opt.isovalues.size());
  TetScratch<D> s{d.template allocate<std::uint8_t>(in.points), d.template allocate<std::uint8_t>(in.tets),
                  d.template allocate<std::uint8_t>(in.tets), d.template allocate<std::uint8_t>(in.tets),
                  d.template allocate<std::uint64_t>(in.tets)};
  std::uint64_t total = 0;
  for (Id k = 0; k < n_iso; ++k) {
    total += count_isovalue(d, in, opt.isovalues[k], s);
    if (3 * total > std::numeric_limits<std::uint32_t>::max())
      throw LimitError("contour: " + std::to_string(total) +
                       " triangles exceed the supported 1431655765 (2^32 - 1 corners)");
  }
  corners = 3 * static_cast<Id>(total);
  auto keys = d.template allocate<std::uint64_t>(corners);
  Id base = 0;
  for (Id k = 0; k < n_iso; ++k) {
    const std::uint64_t triangles = n_iso == 1 ? total : count_isovalue(d, in, opt.isovalues[k], s);
    d.for_each(in.tets, Emit<I>{in.conn, in.P, s.cases.data(), s.first.data(), in.table.data(), ek,
                                static_cast<std::uint64_t>(k), keys.data() + base});
    base += 3 * static_cast<Id>(triangles);
  }
  return keys;
}

// Every point field at the welded points (the contoured one only with
// scalars), then averaged normals: contour(tets)'s fields in its order.
template <class D>
void point_fields(const D& d, const UnstructuredGrid& tets, const Field& field, const ContourOptions& opt,
                  const TetEdgePoints& ep, const device::KeyGroups<D, std::uint64_t>& g, const float* xyz,
                  SurfaceMesh& mesh) {
  const Id points = g.groups;
  for (const Field& f : tets.point_fields) {
    if (&f == &field && !opt.scalars) continue;
    typename D::template Array<float> holder;
    const float* values = device::readable(d, f.values.data(), static_cast<Id>(f.values.size()), holder);
    auto out = d.template allocate<float>(points * f.components);
    d.for_each(points, Tuples{ep, g.unique_keys.data(), values, f.components, &f == &field, out.data()});
    mesh.point_fields.push_back(Field{f.name, f.components, d.to_host(std::move(out))});
  }
  if (opt.normals != ContourNormals::Average) return;
  const auto face =
      device_normals::face_normals(d, xyz, g.index_map.data(), static_cast<Id>(g.index_map.size()) / 3);
  auto normals = device_normals::zero_sums(d, points);
  device::segmented_reduce(d, g.offsets.data(), points, FaceOfPair{g.sorted_pairs.data(), face.data()},
                           device_normals::Add{}, reinterpret_cast<Vec3f*>(normals.data()));
  device_normals::make_unit(d, normals.data(), points);
  mesh.point_fields.push_back(Field{"Normals", 3, d.to_host(std::move(normals))});
}

template <class D, class I>
SurfaceMesh contour_typed(const D& d, const UnstructuredGrid& tets, const I* host_conn, const Field& field,
                          const ContourOptions& opt, ContourStats& st) {
  Input<D, I> in;
  in.tets = tets.num_cells(), in.points = tets.num_points();
  in.conn = device::readable(d, host_conn, 4 * in.tets, in.conn_copy);
  in.P = device::readable(d, tets.points.data(), 3 * in.points, in.points_copy);
  in.S = device::readable(d, field.values.data(), in.points, in.samples_copy);
  in.table = d.upload(&tet_table(), 1);
  in.isovalues = d.upload(opt.isovalues.data(), static_cast<Id>(opt.isovalues.size()));
  const EdgeKeys ek = EdgeKeys::for_points(in.points, "contour");
  const int iso_bits = parallel::bits_needed<std::uint64_t>(opt.isovalues.size() - 1);
  if (ek.key_bits() + iso_bits > 64)
    throw LimitError("contour: edge keys of " + std::to_string(in.points) + " points and " +
                     std::to_string(opt.isovalues.size()) + " isovalues need more than 64 bits");
  st.key_bits = 64;
  Id corners = 0;
  auto keys = emit_soup(d, in, opt, ek, corners);
  st.soup_points = corners;
  device::KeyGroups<D, std::uint64_t> g = device::group_keys(d, keys.data(), corners, ek.key_bits() + iso_bits);
  const TetEdgePoints ep{ek, in.isovalues.data(), in.P, in.S};
  auto xyz = d.template allocate<float>(3 * g.groups);
  d.for_each(g.groups, Positions{ep, g.unique_keys.data(), xyz.data()});
  SurfaceMesh mesh;
  point_fields(d, tets, field, opt, ep, g, xyz.data(), mesh);
  mesh.points = d.to_host(std::move(xyz));
  mesh.connectivity = d.to_host(std::move(g.index_map));
  return mesh;
}

}  // namespace device_tets

// The device path on device `d`: contour(tets)'s input checks, then the
// stages above.
template <class D>
SurfaceMesh contour_tets_on(const D& d, const UnstructuredGrid& tets, const ContourOptions& options,
                            ContourStats* stats = nullptr) {
  const Field& field = check_tet_contour_input(tets, options);
  if (options.weld == ContourWeld::VertexWeld)
    throw InputError("contour: VERTEX-WELD (--weld vertexweld) is not available on the device path (use --backend cpu)");
  if (options.coarsen)
    throw InputError("contour: coarsening (--coarsen) is not available on the device path (use --backend cpu)");
  ContourStats local;
  ContourStats& st = stats ? *stats : local;
  st = ContourStats{};
  if (tets.connectivity.wide())
    return device_tets::contour_typed(d, tets, tets.connectivity.wide_values().data(), field, options, st);
  return device_tets::contour_typed(d, tets, tets.connectivity.narrow().data(), field, options, st);
}

}  // namespace keymesh::generate
