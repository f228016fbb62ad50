#include "keymesh/mesh/fields.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/core/free_storage.hpp"
#include "keymesh/core/progress.hpp"
#include "keymesh/core/uninitialized_array.hpp"
#include "keymesh/generate/unstructured/subdivide_kernels.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/mesh/cell_tables.hpp"
#include "keymesh/mesh/keys.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/keyreduce/weld.hpp"

namespace keymesh::generate {

namespace {

// The parent edges of the pairs, grouped: for every pair, its new point's
// index among the new points (the index map), and for every new point the
// key of its edge. KEY-REDUCE's sort plan, or VERTEX-WELD on the positions
// given by `position(key, xyz)` (the baseline).
struct EdgeGroups {
  std::vector<std::uint64_t> edge_key;     // per new point
  Array<std::uint32_t> index_map;          // per pair
};

template <class Position>
EdgeGroups group_edges(const std::uint64_t* keys, Id n, int key_bits, SubdivideWeld weld, Position&& position) {
  keyreduce::WeldSpec<std::uint64_t> spec;
  spec.plan = weld == SubdivideWeld::KeyReduce ? keyreduce::WeldPlan::Sort : keyreduce::WeldPlan::ByPosition;
  spec.key_bits = key_bits;
  auto g = keyreduce::weld(keys, n, spec, [&](Id i, float* xyz) { position(keys[i], xyz); });
  EdgeGroups out;
  out.edge_key = std::move(g.unique_keys);
  out.index_map = std::move(g.index_map);
  return out;
}

void check_points(Id total, const char* what) {
  if (total > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError(std::string("subdivide: ") + what + " would have " + std::to_string(total) +
                     " points (more than 2^32 - 1)");
}

using subdivision::dot;
using subdivision::load;
using subdivision::V3;

[[noreturn]] void refuse_bezier_without_normals() {
  throw InputError("subdivide --scheme bezier needs point normals (a 3-component \"Normals\" field; "
                   "contour with --normals average or gradient)");
}

SurfaceMesh subdivide_once(const SurfaceMesh& m, SubdivideScheme scheme, SubdivideWeld weld) {
  const Id V = m.num_points(), F = m.num_cells();
  const EdgeKeys ek = EdgeKeys::for_points(V, "subdivide");
  const Field* normals = m.find_point_field("Normals");
  if (normals && normals->components != 3) normals = nullptr;
  if (scheme == SubdivideScheme::Bezier && !normals) refuse_bezier_without_normals();
  const PointIndex* C = m.connectivity.data();
  auto keys = uninitialized_array<std::uint64_t>(static_cast<std::size_t>(3 * F));
  parallel::for_each(F, [&](Id t) {
    for (int e = 0; e < 3; ++e) keys[3 * t + e] = ek(C[3 * t + e], C[3 * t + (e + 1) % 3]);
  });
  // The new point of edge (a, b) and, with Bezier, its normal.
  auto edge_point = [&](std::uint64_t key, float* xyz, float* nrm) {
    const auto [a, b] = ek.decode(key);
    const bool bezier = scheme == SubdivideScheme::Bezier;
    subdivision::edge_point(&m.points[3 * a], &m.points[3 * b], bezier ? &normals->values[3 * a] : nullptr,
                            bezier ? &normals->values[3 * b] : nullptr, xyz, nrm);
  };
  EdgeGroups g = group_edges(keys.get(), 3 * F, ek.key_bits(), weld,
                             [&](std::uint64_t k, float* xyz) { edge_point(k, xyz, nullptr); });
  keys.reset();
  const Id E = static_cast<Id>(g.edge_key.size());
  check_points(V + E, "the surface");

  // Outputs at their final size, written in place; scratch freed after its
  // last pass (the edge keys before the triangles are allocated).
  SurfaceMesh out;
  extend_points(m.points, V + E, out.points);
  out.point_fields = extend_point_fields(m.point_fields, V + E);
  parallel::for_each(E, [&](Id e) {
    const std::uint64_t key = g.edge_key[e];
    const auto [a, b] = ek.decode(key);
    for (std::size_t i = 0; i < m.point_fields.size(); ++i) {
      const Field& f = m.point_fields[i];
      const int k = f.components;
      const bool is_normals = &f == normals;
      if (is_normals && scheme == SubdivideScheme::Bezier) continue;  // set with the position
      subdivision::midpoint_tuple(&f.values[a * k], &f.values[b * k], k, is_normals,
                                  &out.point_fields[i].values[(V + e) * k]);
    }
    float* nrm = nullptr;
    if (scheme == SubdivideScheme::Bezier)
      for (std::size_t i = 0; i < m.point_fields.size(); ++i)
        if (&m.point_fields[i] == normals) nrm = &out.point_fields[i].values[3 * (V + e)];
    edge_point(key, &out.points[3 * (V + e)], nrm);
  });
  free_storage(g.edge_key);
  parallel::resize_fresh(out.connectivity, static_cast<std::size_t>(12 * F));
  parallel::for_each(F, [&](Id t) {
    const PointIndex a = C[3 * t], b = C[3 * t + 1], c = C[3 * t + 2];
    const auto ab = static_cast<PointIndex>(V + g.index_map[3 * t]);
    const auto bc = static_cast<PointIndex>(V + g.index_map[3 * t + 1]);
    const auto ca = static_cast<PointIndex>(V + g.index_map[3 * t + 2]);
    const PointIndex tri[12] = {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca};
    std::copy(tri, tri + 12, &out.connectivity[12 * t]);
  });
  out.cell_fields = repeat_cell_fields(m.cell_fields, F, 4);
  return out;
}

UnstructuredGrid subdivide_tets_once(const UnstructuredGrid& m, SubdivideWeld weld) {
  const Id V = m.num_points(), T = m.num_cells();
  const EdgeKeys ek = EdgeKeys::for_points(V, "subdivide");
  using cells::kTetEdges;
  auto keys = uninitialized_array<std::uint64_t>(static_cast<std::size_t>(6 * T));
  parallel::for_each(T, [&](Id t) {
    for (int e = 0; e < 6; ++e) keys[6 * t + e] = ek(m.connectivity[4 * t + kTetEdges[e][0]], m.connectivity[4 * t + kTetEdges[e][1]]);
  });
  auto midpoint = [&](std::uint64_t key, float* xyz) {
    const auto [a, b] = ek.decode(key);
    for (int c = 0; c < 3; ++c) xyz[c] = 0.5f * (m.points[3 * a + c] + m.points[3 * b + c]);
  };
  EdgeGroups g = group_edges(keys.get(), 6 * T, ek.key_bits(), weld, midpoint);
  keys.reset();
  const Id E = static_cast<Id>(g.edge_key.size());
  check_points(V + E, "the grid");

  UnstructuredGrid out;
  out.uniform_type = CellType::Tetra;
  extend_points(m.points, V + E, out.points);
  out.point_fields = extend_point_fields(m.point_fields, V + E);
  parallel::for_each(E, [&](Id e) {
    const auto [a, b] = ek.decode(g.edge_key[e]);
    midpoint(g.edge_key[e], &out.points[3 * (V + e)]);
    for (std::size_t i = 0; i < m.point_fields.size(); ++i) midpoint_tuple(m.point_fields[i], out.point_fields[i], V + e, a, b);
  });
  free_storage(g.edge_key);
  out.connectivity = IndexArray::for_ids(static_cast<std::uint64_t>(V + E), static_cast<std::size_t>(32 * T));
  const float* P = out.points.data();
  parallel::for_each(T, [&](Id t) {
    std::uint64_t v[10];  // corners 0-3, then the midpoints of edges 01 02 03 12 13 23
    for (int k = 0; k < 4; ++k) v[k] = m.connectivity[4 * t + k];
    for (int e = 0; e < 6; ++e) v[4 + e] = static_cast<std::uint64_t>(V + g.index_map[6 * t + e]);
    std::uint64_t children[8][4];
    subdivision::tet_children(v, P, children);
    for (int c = 0; c < 8; ++c) {
      const std::uint64_t* w = children[c];
      for (int k = 0; k < 4; ++k) out.connectivity.set(static_cast<std::size_t>(32 * t + 4 * c + k), w[k]);
    }
  });
  out.cell_fields = repeat_cell_fields(m.cell_fields, T, 8);
  return out;
}

// Between levels: progress and the chance to abandon (core/progress.hpp).
void report_level(int level, int levels) {
  const std::string stage = "subdivide level " + std::to_string(level + 1) + "/" + std::to_string(levels);
  progress::report(stage.c_str(), static_cast<double>(level) / levels);
}

}  // namespace

void check_subdivide_input(const SurfaceMesh& mesh, const SubdivideOptions& options) {
  if (options.levels < 0) throw InputError("subdivide: --levels must be >= 0");
  if (!mesh.all_triangles()) {
    for (Id c = 0; c < mesh.num_cells(); ++c)
      if (mesh.cell_end(c) - mesh.cell_begin(c) != 3)
        throw InputError("subdivide: cell " + std::to_string(c) + " has " +
                         std::to_string(mesh.cell_end(c) - mesh.cell_begin(c)) + " points; only triangles are subdivided");
  }
  for (const Field& f : mesh.point_fields)
    if (f.values.size() != static_cast<std::size_t>(mesh.num_points() * f.components))
      throw InputError("subdivide: point field '" + f.name + "' does not have one tuple per point");
  for (PointIndex id : mesh.connectivity)
    if (Id{id} >= mesh.num_points()) throw InputError("subdivide: a triangle refers to point " + std::to_string(id) + " out of range");
  // Checked here too (not only as a level starts), so that the GPU's path refuses it before the device is considered.
  const Field* normals = mesh.find_point_field("Normals");
  if (options.levels > 0 && options.scheme == SubdivideScheme::Bezier && (!normals || normals->components != 3))
    refuse_bezier_without_normals();
}

SurfaceMesh subdivided_zero_levels(const SurfaceMesh& mesh) {
  SurfaceMesh out = mesh;
  out.offsets.clear();
  return out;
}

UnstructuredGrid subdivided_zero_levels(const UnstructuredGrid& tets) {
  UnstructuredGrid out = tets;
  out.offsets.clear();
  out.cell_types.clear();
  out.uniform_type = CellType::Tetra;
  return out;
}

SurfaceMesh subdivide(const SurfaceMesh& mesh, const SubdivideOptions& options) {
  check_subdivide_input(mesh, options);
  if (options.levels == 0) return subdivided_zero_levels(mesh);
  // The first level reads the input in place (its cells are triangles, so
  // offsets, if any, are 3 c); no copy of it is held beside the output.
  report_level(0, options.levels);
  SurfaceMesh cur = subdivide_once(mesh, options.scheme, options.weld);
  for (int l = 1; l < options.levels; ++l) {
    report_level(l, options.levels);
    cur = subdivide_once(cur, options.scheme, options.weld);
  }
  return cur;
}

void check_subdivide_input(const UnstructuredGrid& tets, const SubdivideOptions& options) {
  if (options.levels < 0) throw InputError("subdivide: --levels must be >= 0");
  if (options.scheme != SubdivideScheme::Linear)
    throw InputError("subdivide: tetrahedra are subdivided with the linear scheme only");
  if (!tets.all_cells_are(CellType::Tetra)) throw InputError("subdivide: the grid has cells other than tetrahedra");
  tets.validate("subdivide input");
}

UnstructuredGrid subdivide(const UnstructuredGrid& tets, const SubdivideOptions& options) {
  check_subdivide_input(tets, options);
  if (options.levels == 0) return subdivided_zero_levels(tets);
  // The first level reads the input in place (validated tets: 4 corners
  // per cell whatever the offsets say), as the surface's does.
  report_level(0, options.levels);
  UnstructuredGrid cur = subdivide_tets_once(tets, options.weld);
  for (int l = 1; l < options.levels; ++l) {
    report_level(l, options.levels);
    cur = subdivide_tets_once(cur, options.weld);
  }
  return cur;
}

}  // namespace keymesh::generate
