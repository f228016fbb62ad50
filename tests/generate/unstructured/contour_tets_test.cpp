#include "keymesh/generate/unstructured/contour_tets.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <vector>

#include "keymesh/analyze/topology.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "keymesh/parallel/threads.hpp"
#include "mesh_measures.hpp"

using namespace keymesh;
using generate::ContourNormals;
using generate::ContourOptions;
using generate::ContourWeld;
using test::enclosed_volume;

namespace {

ContourOptions iso(double v, ContourNormals normals = ContourNormals::None, ContourWeld weld = ContourWeld::KeyReduce) {
  ContourOptions o;
  o.isovalues = {v};
  o.normals = normals;
  o.weld = weld;
  return o;
}

// Every directed edge used once and its reverse once: consistent winding.
bool consistently_wound(const SurfaceMesh& m) {
  std::map<std::pair<PointIndex, PointIndex>, int> directed;
  for (Id t = 0; t < m.num_cells(); ++t)
    for (int e = 0; e < 3; ++e) ++directed[{m.connectivity[3 * t + e], m.connectivity[3 * t + (e + 1) % 3]}];
  for (const auto& [edge, n] : directed)
    if (n != 1 || !directed.count({edge.second, edge.first})) return false;
  return true;
}

// Edges of the tet mesh whose ends straddle the isovalue: the expected point count.
Id straddling_edges(const UnstructuredGrid& g, const Array<float>& s, double v) {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> edges;
  for (Id t = 0; t < g.num_cells(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        std::uint64_t p = g.connectivity[4 * t + a], q = g.connectivity[4 * t + b];
        if ((s[p] >= v) != (s[q] >= v)) edges.push_back({std::min(p, q), std::max(p, q)});
      }
  std::sort(edges.begin(), edges.end());
  return Id(std::unique(edges.begin(), edges.end()) - edges.begin());
}

// The 5-tet sphere grid with a second field, x + 2y, to check interpolation.
UnstructuredGrid sphere_tets(Id n) {
  UnstructuredGrid g = generate::tetrahedralize5(generate::spherical_distance(n));
  Field lin{"linear", 1, Array<float>(g.num_points(), 0.f)};
  for (Id p = 0; p < g.num_points(); ++p) lin.values[p] = g.points[3 * p] + 2 * g.points[3 * p + 1];
  g.point_fields.push_back(lin);
  return g;
}

TEST(ContourTets, SphereIsAClosedOutwardManifold) {
  const Id n = 32;
  const UnstructuredGrid g = sphere_tets(n);
  const double v = n / 2.0 - 1.5;
  const SurfaceMesh m = generate::contour(g, iso(v));
  const auto topo = analyze::check_topology(m);
  EXPECT_TRUE(topo.closed_manifold);
  EXPECT_EQ(topo.euler_characteristic, 2);
  EXPECT_EQ(topo.duplicate_points, 0);
  EXPECT_EQ(topo.components, 1);
  EXPECT_TRUE(consistently_wound(m));
  EXPECT_EQ(m.num_points(), straddling_edges(g, g.point_fields[0].values, v));
  // The distance field grows outward, so inside (>= iso) is the outside of
  // the ball: triangles point from there to the lower values, into the ball,
  // and the enclosed volume comes out negative, near the ball's.
  const double ball = 4.0 / 3.0 * std::acos(-1.0) * std::pow(v, 3);
  EXPECT_LT(enclosed_volume(m), 0);
  EXPECT_NEAR(-enclosed_volume(m), ball, 0.05 * ball);
}

TEST(ContourTets, FieldsAreInterpolated) {
  const UnstructuredGrid g = sphere_tets(16);
  const SurfaceMesh m = generate::contour(g, iso(6.3, ContourNormals::Average));
  const Field* s = m.find_point_field(g.point_fields[0].name);
  const Field* lin = m.find_point_field("linear");
  const Field* nrm = m.find_point_field("Normals");
  ASSERT_TRUE(s && lin && nrm);
  for (Id p = 0; p < m.num_points(); ++p) {
    ASSERT_NEAR(s->values[p], 6.3, 1e-4);
    // A linear field interpolates exactly along an edge.
    ASSERT_NEAR(lin->values[p], m.points[3 * p] + 2 * m.points[3 * p + 1], 1e-4);
    const float* nn = &nrm->values[3 * p];
    ASSERT_NEAR(std::sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]), 1.0, 1e-5);
    // Normals point to lower values: towards the centre (7.5, 7.5, 7.5).
    const double r[3] = {m.points[3 * p] - 7.5, m.points[3 * p + 1] - 7.5, m.points[3 * p + 2] - 7.5};
    ASSERT_LT(r[0] * nn[0] + r[1] * nn[1] + r[2] * nn[2], 0);
  }
}

TEST(ContourTets, ShuffledIdsAndCornerOrdersWeldTheSame) {
  // The same tets with point ids permuted, each tet's corners in a random
  // order (odd permutations make left-handed tets) and the tets shuffled:
  // shared edges are listed in every order. The surface must not change.
  const UnstructuredGrid g = sphere_tets(20);
  const SurfaceMesh ref = generate::contour(g, iso(8.2));
  std::mt19937 rng(7);
  const Id np = g.num_points(), nt = g.num_cells();
  std::vector<std::uint64_t> perm(np);
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);
  UnstructuredGrid h;
  h.points.resize(g.points.size());
  Field f{"s", 1, Array<float>(np, 0.f)};
  for (Id p = 0; p < np; ++p) {
    std::copy_n(&g.points[3 * p], 3, &h.points[3 * perm[p]]);
    f.values[perm[p]] = g.point_fields[0].values[p];
  }
  h.point_fields.push_back(f);
  std::vector<Id> tet_order(nt);
  std::iota(tet_order.begin(), tet_order.end(), 0);
  std::shuffle(tet_order.begin(), tet_order.end(), rng);
  h.connectivity = IndexArray::for_ids(np, 4 * nt);
  for (Id t = 0; t < nt; ++t) {
    std::array<std::uint64_t, 4> c;
    for (int k = 0; k < 4; ++k) c[k] = perm[g.connectivity[4 * tet_order[t] + k]];
    std::shuffle(c.begin(), c.end(), rng);
    for (int k = 0; k < 4; ++k) h.connectivity.set(4 * t + k, c[k]);
  }
  const SurfaceMesh m = generate::contour(h, iso(8.2));
  EXPECT_EQ(m.num_points(), ref.num_points());
  EXPECT_EQ(m.num_cells(), ref.num_cells());
  const auto topo = analyze::check_topology(m);
  EXPECT_TRUE(topo.closed_manifold);
  EXPECT_EQ(topo.euler_characteristic, 2);
  EXPECT_TRUE(consistently_wound(m));
  EXPECT_NEAR(enclosed_volume(m), enclosed_volume(ref), 1e-6 * std::abs(enclosed_volume(ref)));
  // The same points, up to the last bit where the smaller id changed ends.
  // (Triangles may differ: a quad cut in a tet is split along a diagonal
  // chosen by the tet's local corner order, as in VTK's tables.)
  auto a = test::sorted_points(ref), b = test::sorted_points(m);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    for (int x = 0; x < 3; ++x) ASSERT_NEAR(a[i][x], b[i][x], 1e-5) << "point " << i;
}

TEST(ContourTets, VertexWeldAndThreadsAgree) {
  const UnstructuredGrid g = sphere_tets(24);
  ContourOptions several = iso(5.5, ContourNormals::Average);
  several.isovalues.push_back(9.25);
  const SurfaceMesh one = test::expect_threads_and_vertex_weld_agree([&](bool by_position) {
    several.weld = by_position ? ContourWeld::VertexWeld : ContourWeld::KeyReduce;
    return generate::contour(g, several);
  });
  const auto topo = analyze::check_topology(one);
  EXPECT_EQ(topo.components, 2);
  EXPECT_TRUE(topo.closed_manifold);
}

TEST(ContourTets, RefusesWhatItCannotContour) {
  UnstructuredGrid g = sphere_tets(4);
  EXPECT_THROW(generate::contour(g, iso(1.0, ContourNormals::Gradient)), InputError);
  ContourOptions named = iso(1.0);
  named.array = "nope";
  EXPECT_THROW(generate::contour(g, named), InputError);
  EXPECT_THROW(generate::contour(g, iso(std::nan(""))), InputError);
  g.connectivity.set(5, 1u << 20);  // out of range
  EXPECT_THROW(generate::contour(g, iso(1.0)), InputError);
  UnstructuredGrid hexes;
  hexes.points.assign(24, 0.f);
  hexes.uniform_type = CellType::Hexahedron;
  hexes.connectivity = IndexArray::for_ids(8, 8);
  hexes.point_fields.push_back({"s", 1, Array<float>(8, 0.f)});
  EXPECT_THROW(generate::contour(hexes, iso(1.0)), InputError);
}

TEST(ContourTets, NanSamplesNeverGiveNanPoints) {
  UnstructuredGrid g = sphere_tets(12);
  auto& s = g.point_fields[0].values;
  for (std::size_t p = 0; p < s.size(); p += 7) s[p] = std::nanf("");
  const SurfaceMesh m = generate::contour(g, iso(4.5));
  ASSERT_GT(m.num_points(), 0);
  for (float x : m.points) ASSERT_TRUE(std::isfinite(x));
  for (const Field& f : m.point_fields)
    for (float x : f.values) ASSERT_TRUE(std::isfinite(x)) << f.name;
}

}  // namespace
