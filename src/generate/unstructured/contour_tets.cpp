#include "keymesh/generate/unstructured/contour_tets.hpp"

#include <chrono>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <tuple>
#include <utility>

#include "keymesh/core/error.hpp"
#include "keymesh/core/free_storage.hpp"
#include "keymesh/core/uninitialized_array.hpp"
#include "keymesh/generate/coarsen/coarsen.hpp"
#include "keymesh/generate/unstructured/tet_kernels.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "keymesh/generate/contour/contour_kernels.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/mesh/cell_tables.hpp"
#include "keymesh/mesh/keys.hpp"
#include "keymesh/keyreduce/weld.hpp"
#include "keymesh/keyreduce/reduce.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"
#include "keymesh/weld/vertex_weld.hpp"
#include "generate/contour/history_t.hpp"

namespace keymesh::generate {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

using cells::kTetEdges;

int edge_of(int a, int b) {
  for (int e = 0; e < 6; ++e)
    if ((kTetEdges[e][0] == a && kTetEdges[e][1] == b) || (kTetEdges[e][0] == b && kTetEdges[e][1] == a)) return e;
  return -1;
}

// The case table (tet_kernels.hpp): one corner apart from the others gives a
// triangle, two and two a quad cut into two triangles along a diagonal inside
// the tet, each wound on the reference tet to point from inside to outside.
TetTable build_tet_table() {
  TetTable table{};
  std::uint8_t (&triangles)[16] = table.triangles;
  std::uint8_t (&edges)[16][6] = table.edges;
  const double ref[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int m = 0; m < 16; ++m) {
    int in[4], out[4], ni = 0, no = 0;
    for (int v = 0; v < 4; ++v) ((m >> v) & 1 ? in[ni++] : out[no++]) = v;
    int tri[2][3];
    int nt = 0;
    if (ni == 1 || ni == 3) {
      const int apex = ni == 1 ? in[0] : out[0];
      int k = 0;
      for (int v = 0; v < 4; ++v)
        if (v != apex) tri[0][k++] = edge_of(apex, v);
      nt = 1;
    } else if (ni == 2) {
      const int a = in[0], b = in[1], c = out[0], d = out[1];
      const int ac = edge_of(a, c), ad = edge_of(a, d), bd = edge_of(b, d), bc = edge_of(b, c);
      tri[0][0] = ac, tri[0][1] = ad, tri[0][2] = bd;
      tri[1][0] = ac, tri[1][1] = bd, tri[1][2] = bc;
      nt = 2;
    }
    triangles[m] = static_cast<std::uint8_t>(nt);
    double dir[3] = {0, 0, 0};  // from the inside corners' centroid to the outside ones'
    for (int v = 0; v < 4; ++v)
      for (int a = 0; a < 3; ++a) dir[a] += ((m >> v) & 1 ? -1.0 / ni : 1.0 / no) * ref[v][a];
    for (int t = 0; t < nt; ++t) {
      double p[3][3];
      for (int c = 0; c < 3; ++c)
        for (int a = 0; a < 3; ++a)
          p[c][a] = 0.5 * (ref[kTetEdges[tri[t][c]][0]][a] + ref[kTetEdges[tri[t][c]][1]][a]);
      const double u[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
      const double w[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
      const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
      if (n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2] < 0) std::swap(tri[t][1], tri[t][2]);
      for (int c = 0; c < 3; ++c) edges[m][3 * t + c] = static_cast<std::uint8_t>(tri[t][c]);
    }
  }
  return table;
}

}  // namespace

const TetTable& tet_table() {
  static const TetTable table = build_tet_table();
  return table;
}

namespace {

// Tets per chunk of the counting pass: fixed, so the work split never
// changes the output (which is in tet order anyway).
constexpr Id kTetsPerChunk = Id{1} << 14;

// Appends one isovalue's soup (an edge key per triangle corner) to `keys`.
template <class I>
void tet_soup(const I* conn, Id tets, Id points, const float* P, const float* scalars, double iso,
              std::uint64_t iso_index, const EdgeKeys& ek, std::uint8_t* inside, std::uint8_t* cases,
              std::vector<std::uint64_t>& keys, ContourStats& st) {
  const auto& table = tet_table();
  auto t0 = Clock::now();
  parallel::for_each(points, [&](Id p) { inside[p] = static_cast<std::uint8_t>(scalars[p] >= iso); });
  const Id chunks = (tets + kTetsPerChunk - 1) / kTetsPerChunk;
  std::vector<Id> chunk_offset(static_cast<std::size_t>(chunks + 1), 0);
  std::vector<std::uint8_t> chunk_bad(static_cast<std::size_t>(chunks), 0);
  parallel::for_each_dynamic(chunks, [&](Id c) {
    const Id end = std::min(tets, (c + 1) * kTetsPerChunk);
    Id count = 0;
    for (Id t = c * kTetsPerChunk; t < end; ++t) {
      const I* v = conn + 4 * t;
      if (std::max(std::max(v[0], v[1]), std::max(v[2], v[3])) >= static_cast<std::uint64_t>(points)) {
        chunk_bad[c] = 1;
        cases[t] = 0;
        continue;
      }
      const unsigned m = inside[v[0]] | (inside[v[1]] << 1) | (inside[v[2]] << 2) | (inside[v[3]] << 3);
      cases[t] = static_cast<std::uint8_t>(m);
      count += table.triangles[m];
    }
    chunk_offset[c] = count;
  }, 4);
  for (Id c = 0; c < chunks; ++c)
    if (chunk_bad[c])
      for (Id t = c * kTetsPerChunk; t < std::min(tets, (c + 1) * kTetsPerChunk); ++t)
        for (int k = 0; k < 4; ++k)
          if (static_cast<std::uint64_t>(conn[4 * t + k]) >= static_cast<std::uint64_t>(points))
            throw InputError("contour input: point id " + std::to_string(std::uint64_t(conn[4 * t + k])) +
                             " of tet " + std::to_string(t) + " is out of range (" + std::to_string(points) +
                             " points)");
  const Id triangles = parallel::exclusive_scan(chunk_offset.data(), chunk_offset.data(), chunks + 1);
  st.classify += seconds_since(t0);
  t0 = Clock::now();
  const Id base = static_cast<Id>(keys.size());
  if (base + 3 * triangles > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("contour: " + std::to_string(base / 3 + triangles) +
                     " triangles exceed the supported 1431655765 (2^32 - 1 corners)");
  keys.resize(static_cast<std::size_t>(base + 3 * triangles));
  std::uint64_t* out = keys.data() + base;
  parallel::for_each_dynamic(chunks, [&](Id c) {
    const Id end = std::min(tets, (c + 1) * kTetsPerChunk);
    std::uint64_t* o = out + 3 * chunk_offset[c];
    for (Id t = c * kTetsPerChunk; t < end; ++t) {
      // Skip eight uncut tets at a time (most of the grid).
      if ((t & 7) == 0 && t + 8 <= end) {
        std::uint64_t w;
        std::memcpy(&w, cases + t, 8);
        if (w == 0 || w == 0x0F0F0F0F0F0F0F0Full) {
          t += 7;
          continue;
        }
      }
      const unsigned m = cases[t];
      if (m == 0 || m == 15) continue;
      const I* v = conn + 4 * t;
      // A left-handed tet would turn its triangles inside out: wind them back.
      const bool flip =
          tet_volume(P + 3 * std::uint64_t(v[0]), P + 3 * std::uint64_t(v[1]), P + 3 * std::uint64_t(v[2]),
                     P + 3 * std::uint64_t(v[3])) < 0;
      for (int tri = 0; tri < table.triangles[m]; ++tri)
        for (int corner = 0; corner < 3; ++corner) {
          const int e = table.edges[m][3 * tri + (flip && corner ? 3 - corner : corner)];
          *o++ = ek.with_level(ek(v[kTetEdges[e][0]], v[kTetEdges[e][1]]), iso_index);
        }
    }
  }, 4);
  st.generate += seconds_since(t0);
}

// The map step over every isovalue: an edge key per triangle corner.
std::vector<std::uint64_t> tet_soups(const UnstructuredGrid& tets, const ContourOptions& opt, const TetEdgePoints& ep,
                                     ContourStats& st) {
  std::vector<std::uint64_t> soup;
  // Left uninitialised (every entry is written before it is read), so
  // the pages are first touched by the parallel passes, not by a serial
  // memset; freed before the weld. (Kept across calls instead, as the voxel
  // contour keeps its bits, they cost their bytes in every later stage's
  // peak for no measurable gain: measured, ops_bench --op tetcontour.)
  const auto inside = uninitialized_array<std::uint8_t>(static_cast<std::size_t>(tets.num_points()));
  const auto cases = uninitialized_array<std::uint8_t>(static_cast<std::size_t>(tets.num_cells()));
  tets.connectivity.visit([&](auto conn) {
    for (std::size_t k = 0; k < opt.isovalues.size(); ++k)
      tet_soup(conn.data(), tets.num_cells(), tets.num_points(), ep.P, ep.S, opt.isovalues[k], k, ep.ek, inside.get(),
               cases.get(), soup, st);
  });
  return soup;
}

// Every point field of the grid at the welded points, interpolated along
// the points' edges (the contoured field only with opt.scalars).
void interpolate_fields(const UnstructuredGrid& tets, const Field& field, const ContourOptions& opt,
                        const TetEdgePoints& ep, const keyreduce::Groups<std::uint64_t>& groups, SurfaceMesh& mesh) {
  const Id points = groups.num_groups();
  const std::uint64_t* point_key = groups.unique_keys.data();
  for (const Field& f : tets.point_fields) {
    if (&f == &field && !opt.scalars) continue;
    const int k = f.components;
    Field g{f.name, k, {}};
    parallel::resize_fresh(g.values, static_cast<std::size_t>(points) * static_cast<std::size_t>(k));
    // The contoured field at a NaN end takes the isovalue; others keep a finite end.
    parallel::for_each(points, [&](Id p) { ep.tuple(point_key[p], f.values.data(), k, &f == &field, &g.values[p * k]); });
    mesh.point_fields.push_back(std::move(g));
  }
}

// History (contour_tets.hpp): each point's t, as the float that gives its
// three written coordinates back (its key is groups.unique_keys).
void add_history_t(const TetEdgePoints& ep, const keyreduce::Groups<std::uint64_t>& groups, SurfaceMesh& mesh) {
  const Id points = groups.num_groups();
  Field history{"history_t", 1, {}};
  parallel::resize_fresh(history.values, static_cast<std::size_t>(points));
  parallel::for_each(points, [&](Id p) {
    const TetEdgePoint e = ep.locate(groups.unique_keys[p]);
    const float* written = &mesh.points[3 * p];
    history.values[p] = nearest_float_t(e.t, [&](float t) {
      for (int a = 0; a < 3; ++a) {
        const double pa = ep.P[3 * e.a + a], pb = ep.P[3 * e.b + a];
        if (static_cast<float>(pa + static_cast<double>(t) * (pb - pa)) != written[a]) return false;
      }
      return true;
    });
  });
  mesh.point_fields.push_back(std::move(history));
}

// Coarsening: every point's coarse key is its edge's end point nearest to
// the crossing, per isovalue.
SurfaceMesh coarsen_contour(SurfaceMesh mesh, const TetEdgePoints& ep, const std::vector<std::uint64_t>& point_key,
                            Id points_in, std::size_t isovalues, bool average, ContourStats& st) {
  const Id points = mesh.num_points();
  std::vector<std::uint64_t> coarse(static_cast<std::size_t>(points));
  parallel::for_each(points, [&](Id p) {
    const TetEdgePoint e = ep.locate(point_key[p]);
    coarse[p] = ep.ek.level(point_key[p]) * static_cast<std::uint64_t>(points_in) + (e.t >= 0.5 ? e.b : e.a);
  });
  st.triangles_before_coarsening = mesh.num_cells();
  mesh = coarsen(mesh, coarse, static_cast<std::uint64_t>(points_in) * isovalues);
  if (average) average_normals(mesh);
  return mesh;
}

}  // namespace

const Field& check_tet_contour_input(const UnstructuredGrid& tets, const ContourOptions& opt) {
  if (opt.isovalues.empty()) throw InputError("contour: no isovalue given");
  for (double iso : opt.isovalues)
    if (!std::isfinite(iso)) throw InputError("contour: isovalue " + std::to_string(iso) + " is not finite");
  if (opt.normals == ContourNormals::Gradient)
    throw InputError("contour: --normals gradient needs a voxel grid; use --normals average on tetrahedra");
  if (opt.curvature)
    throw InputError("contour: --curvature needs a voxel grid (it reads the volume's Hessian)");
  if (!tets.all_cells_are(CellType::Tetra))
    throw InputError("contour: the grid has cells other than tetrahedra (tetrahedralize it first)");
  tets.validate("contour input", /*check_ids=*/false);  // ids are checked as the tets are classified
  const Field* field = nullptr;
  for (const Field& f : tets.point_fields)
    if (opt.array.empty() ? f.components == 1 : f.name == opt.array) {
      field = &f;
      break;
    }
  if (!field)
    throw InputError(opt.array.empty() ? "contour: the grid has no one-component point field to contour"
                                       : "contour: the grid has no point field '" + opt.array + "'");
  if (field->components != 1)
    throw InputError("contour: point field '" + field->name + "' has " + std::to_string(field->components) +
                     " components (need 1)");
  return *field;
}

SurfaceMesh contour(const UnstructuredGrid& tets, const ContourOptions& opt, ContourStats* stats,
                    std::vector<std::uint64_t>* point_keys) {
  const Field& field = check_tet_contour_input(tets, opt);
  // The GPU is reached through keymesh/backend/contour.hpp (the layer above generate and cuda).
  if (opt.backend != Backend::Cpu)
    throw InputError("--backend cuda: generate::contour runs on the CPU (backend::contour chooses the GPU)");
  if (opt.coarsen && (opt.history || point_keys))
    throw InputError("contour: --history with --coarsen: a coarsened point merges crossings of several edges, "
                     "so it has no one edge and t (docs/HISTORY.md)");
  ContourStats local;
  ContourStats& st = stats ? *stats : local;
  st = ContourStats{};
  const Id points_in = tets.num_points();
  const TetEdgePoints ep{EdgeKeys::for_points(points_in, "contour"), opt.isovalues.data(), tets.points.data(),
                         field.values.data()};
  const int iso_bits = parallel::bits_needed<std::uint64_t>(opt.isovalues.size() - 1);
  if (ep.ek.key_bits() + iso_bits > 64)
    throw LimitError("contour: edge keys of " + std::to_string(points_in) + " points and " +
                     std::to_string(opt.isovalues.size()) + " isovalues need more than 64 bits");
  st.key_bits = 64;
  std::vector<std::uint64_t> soup = tet_soups(tets, opt, ep, st);
  const Id corners = static_cast<Id>(soup.size());
  st.soup_points = corners;

  // Weld: both KEY-REDUCE plan names use the sort plan here (N^2 edge keys
  // are too many to address directly); VERTEX-WELD by position.
  SurfaceMesh mesh;
  const bool average = opt.normals == ContourNormals::Average;
  auto t0 = Clock::now();
  const bool by_position = opt.weld == ContourWeld::VertexWeld;
  keyreduce::WeldSpec<std::uint64_t> spec;
  spec.plan = by_position ? keyreduce::WeldPlan::ByPosition : keyreduce::WeldPlan::Sort;
  spec.key_bits = ep.ek.key_bits() + iso_bits;
  spec.order = average ? keyreduce::Order::Build : keyreduce::Order::Skip;
  // The soup is given up: the sort plan sorts it in place (VERTEX-WELD
  // reads it, through `position`, and leaves it).
  keyreduce::Groups<std::uint64_t> groups =
      keyreduce::weld(std::move(soup), spec, [&](Id c, float* xyz) { ep.position(soup[c], xyz); },
                      {by_position ? &mesh.points : nullptr, nullptr});
  // The index map is the connectivity (no copy); the soup is freed before
  // the points are allocated.
  mesh.connectivity = std::move(groups.index_map);
  free_storage(soup);
  st.weld += seconds_since(t0);

  // Reduce: positions, fields, normals.
  t0 = Clock::now();
  const Id points = groups.num_groups();
  if (mesh.points.empty()) {
    parallel::resize_fresh(mesh.points, static_cast<std::size_t>(3 * points));
    parallel::for_each(points, [&](Id p) { ep.position(groups.unique_keys[p], &mesh.points[3 * p]); });
  }
  interpolate_fields(tets, field, opt, ep, groups, mesh);
  if (opt.history) add_history_t(ep, groups, mesh);
  if (point_keys) point_keys->assign(groups.unique_keys.begin(), groups.unique_keys.end());
  if (average && !opt.coarsen) {
    // The weld's groups are the corners grouped by point (mesh/normals.hpp),
    // summed into the field itself.
    Field normals{"Normals", 3, {}};
    parallel::resize_fresh(normals.values, static_cast<std::size_t>(3 * points));
    auto* sums = reinterpret_cast<Vec3f*>(normals.values.data());
    sum_face_normals(groups, face_normals(mesh).data(), sums);
    normalize(sums, points);
    mesh.point_fields.push_back(std::move(normals));
  }
  st.fields += seconds_since(t0);
  if (opt.coarsen) {
    t0 = Clock::now();
    mesh = coarsen_contour(std::move(mesh), ep, groups.unique_keys, points_in, opt.isovalues.size(), average, st);
    st.coarsen += seconds_since(t0);
  }
  return mesh;
}

}  // namespace keymesh::generate
