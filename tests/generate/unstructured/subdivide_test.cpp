#include "mesh_measures.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <vector>

#include "keymesh/analyze/topology.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "keymesh/parallel/threads.hpp"

using namespace keymesh;
using generate::SubdivideOptions;
using generate::SubdivideScheme;
using generate::SubdivideWeld;

namespace {

SurfaceMesh sphere_surface(Id n, double iso) {
  generate::ContourOptions o;
  o.isovalues = {iso};
  o.normals = generate::ContourNormals::Average;
  return generate::contour(generate::spherical_distance(n), o);
}

Id distinct_edges(const SurfaceMesh& m) {
  std::set<std::pair<PointIndex, PointIndex>> e;
  for (Id t = 0; t < m.num_cells(); ++t)
    for (int k = 0; k < 3; ++k) {
      const PointIndex a = m.connectivity[3 * t + k], b = m.connectivity[3 * t + (k + 1) % 3];
      e.insert({std::min(a, b), std::max(a, b)});
    }
  return Id(e.size());
}

// Largest distance of a point from the sphere of radius r around c.
double max_deviation(const SurfaceMesh& m, double c, double r) {
  double worst = 0;
  for (Id p = 0; p < m.num_points(); ++p) {
    const double x = m.points[3 * p] - c, y = m.points[3 * p + 1] - c, z = m.points[3 * p + 2] - c;
    worst = std::max(worst, std::abs(std::sqrt(x * x + y * y + z * z) - r));
  }
  return worst;
}

TEST(SubdivideTriangles, CountsAndTopologyPerLevel) {
  const SurfaceMesh m = sphere_surface(24, 10.5);
  const Id V = m.num_points(), F = m.num_cells(), E = distinct_edges(m);
  SubdivideOptions o;
  const SurfaceMesh one = generate::subdivide(m, o);
  EXPECT_EQ(one.num_points(), V + E);
  EXPECT_EQ(one.num_cells(), 4 * F);
  o.levels = 2;
  const SurfaceMesh two = generate::subdivide(m, o);
  EXPECT_EQ(two.num_points(), one.num_points() + distinct_edges(one));
  EXPECT_EQ(two.num_cells(), 16 * F);
  for (const SurfaceMesh* s : {&one, &two}) {
    const auto t = analyze::check_topology(*s);
    EXPECT_TRUE(t.closed_manifold);
    EXPECT_EQ(t.euler_characteristic, 2);
    EXPECT_EQ(t.duplicate_points, 0);
  }
  // Old points pass through; fields are carried (scalars stay at the isovalue on a
  // linear field along each edge: the average of two values of 10.5 +- rounding).
  EXPECT_TRUE(std::equal(m.points.begin(), m.points.end(), one.points.begin()));
  const Field* s = one.find_point_field("distance");
  ASSERT_NE(s, nullptr);
  for (float v : s->values) ASSERT_NEAR(v, 10.5, 1e-4);
  const Field* n = one.find_point_field("Normals");
  ASSERT_NE(n, nullptr);
  for (Id p = 0; p < one.num_points(); ++p)
    ASSERT_NEAR(std::hypot(n->values[3 * p], n->values[3 * p + 1], n->values[3 * p + 2]), 1.0, 1e-5);
  // A linear new point is the midpoint of the input edge it splits: corner k
  // of triangle t and the next corner (child triangle k lists them first).
  for (Id t = 0; t < m.num_cells(); ++t) {
    const PointIndex a = m.connectivity[3 * t], b = m.connectivity[3 * t + 1];
    const PointIndex ab = one.connectivity[12 * t + 1];
    for (int x = 0; x < 3; ++x)
      ASSERT_FLOAT_EQ(one.points[3 * ab + x], 0.5f * (m.points[3 * a + x] + m.points[3 * b + x]));
  }
}

TEST(SubdivideTriangles, BezierStaysCloserToTheSphere) {
  const SurfaceMesh m = sphere_surface(48, 20.5);
  SubdivideOptions o;
  o.levels = 2;
  const double lin = max_deviation(generate::subdivide(m, o), 24, 20.5);
  o.scheme = SubdivideScheme::Bezier;
  const SurfaceMesh b = generate::subdivide(m, o);
  const double bez = max_deviation(b, 24, 20.5);
  EXPECT_LT(bez, lin);
  const auto t = analyze::check_topology(b);
  EXPECT_TRUE(t.closed_manifold);
  EXPECT_EQ(t.euler_characteristic, 2);
  ASSERT_NE(b.find_point_field("Normals"), nullptr);
  ASSERT_NE(b.find_point_field("distance"), nullptr);
}

TEST(SubdivideTriangles, VertexWeldAndThreadCountsAgree) {
  const SurfaceMesh m = sphere_surface(20, 8.5);
  SubdivideOptions o;
  o.scheme = SubdivideScheme::Bezier;
  test::expect_threads_and_vertex_weld_agree([&](bool by_position) {
    o.weld = by_position ? SubdivideWeld::VertexWeld : SubdivideWeld::KeyReduce;
    return generate::subdivide(m, o);
  });
}

TEST(SubdivideTriangles, ChildrenKeepTheirParentsCellFields) {
  // A cell field (e.g. labels' boundary_labels) follows the split: the
  // four children of triangle t are 4t..4t+3 and carry t's tuple.
  SurfaceMesh m = sphere_surface(16, 5.3);
  Field f{"pair", 2, {}};
  for (Id t = 0; t < m.num_cells(); ++t) f.values.insert(f.values.end(), {float(t), float(-t)});
  m.cell_fields.push_back(f);
  SubdivideOptions o;
  o.levels = 2;
  const SurfaceMesh s = generate::subdivide(m, o);
  ASSERT_EQ(s.cell_fields.size(), 1u);
  ASSERT_EQ(s.cell_fields[0].values.size(), 2 * static_cast<std::size_t>(s.num_cells()));
  ASSERT_EQ(s.num_cells(), 16 * m.num_cells());
  for (Id c = 0; c < s.num_cells(); ++c) {
    EXPECT_EQ(s.cell_fields[0].values[2 * c], float(c / 16)) << c;
    EXPECT_EQ(s.cell_fields[0].values[2 * c + 1], -float(c / 16)) << c;
  }
}

TEST(SubdivideTriangles, RefusesWhatItCannotDo) {
  SurfaceMesh quad;
  quad.points = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  quad.connectivity = {0, 1, 2, 3};
  quad.offsets = {0, 4};
  EXPECT_THROW(generate::subdivide(quad, SubdivideOptions{}), InputError);
  SurfaceMesh tri;
  tri.points = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  tri.connectivity = {0, 1, 2};
  SubdivideOptions o;
  o.scheme = SubdivideScheme::Bezier;
  EXPECT_THROW(generate::subdivide(tri, o), InputError);
  tri.connectivity = {0, 1, 7};
  EXPECT_THROW(generate::subdivide(tri, SubdivideOptions{}), InputError);
}

double volume_of(const UnstructuredGrid& g, bool& all_positive) {
  double sum = 0;
  all_positive = true;
  for (Id t = 0; t < g.num_cells(); ++t) {
    const float* P = g.points.data();
    const double v = generate::tet_volume(P + 3 * g.connectivity[4 * t], P + 3 * g.connectivity[4 * t + 1],
                                          P + 3 * g.connectivity[4 * t + 2], P + 3 * g.connectivity[4 * t + 3]);
    all_positive = all_positive && v > 0;
    sum += v;
  }
  return sum;
}

TEST(SubdivideTets, OneToEightConformingAndVolumePreserving) {
  ImageGrid grid = generate::spherical_distance(5);
  grid.spacing = {1.0, 0.5, 2.0};
  const UnstructuredGrid g = generate::tetrahedralize5(grid);
  std::set<std::pair<std::uint64_t, std::uint64_t>> edges;
  for (Id t = 0; t < g.num_cells(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const std::uint64_t p = g.connectivity[4 * t + a], q = g.connectivity[4 * t + b];
        edges.insert({std::min(p, q), std::max(p, q)});
      }
  const UnstructuredGrid s = generate::subdivide(g, SubdivideOptions{});
  EXPECT_EQ(s.num_cells(), 8 * g.num_cells());
  EXPECT_EQ(s.num_points(), g.num_points() + Id(edges.size()));
  bool positive = false;
  const double before = volume_of(g, positive);
  const double after = volume_of(s, positive);
  EXPECT_TRUE(positive);
  EXPECT_NEAR(after, before, 1e-9 * before);
  std::map<std::array<std::uint64_t, 3>, int> use;
  for (Id t = 0; t < s.num_cells(); ++t)
    for (int skip = 0; skip < 4; ++skip) {
      std::array<std::uint64_t, 3> f{};
      int k = 0;
      for (int v = 0; v < 4; ++v)
        if (v != skip) f[k++] = s.connectivity[4 * t + v];
      std::sort(f.begin(), f.end());
      ++use[f];
    }
  Id boundary = 0;
  for (const auto& [f, n] : use) {
    ASSERT_LE(n, 2);
    boundary += n == 1;
  }
  EXPECT_EQ(boundary, 4 * 2 * 6 * 4 * 4);  // 4x the 2 triangles of each of the box's 6 x 4 x 4 quads
  const Field* f = s.find_point_field("distance");
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->values.size(), std::size_t(s.num_points()));
}

}  // namespace
