#include "keymesh/generate/coarsen.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>

#include "keymesh/analyze/quality.hpp"
#include "keymesh/analyze/topology.hpp"
#include "keymesh/generate/contour.hpp"
#include "keymesh/generate/contour_tets.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/generate/tetrahedralize.hpp"
#include "keymesh/parallel/threads.hpp"

using namespace keymesh;

namespace {

generate::ContourOptions options(double iso, bool coarsen, generate::ContourNormals n = generate::ContourNormals::None) {
  generate::ContourOptions o;
  o.isovalues = {iso};
  o.coarsen = coarsen;
  o.normals = n;
  return o;
}

Id duplicate_triangles(const SurfaceMesh& m) {
  std::set<std::array<PointIndex, 3>> seen;
  Id dup = 0;
  for (Id t = 0; t < m.num_cells(); ++t) {
    std::array<PointIndex, 3> c{m.connectivity[3 * t], m.connectivity[3 * t + 1], m.connectivity[3 * t + 2]};
    std::sort(c.begin(), c.end());
    dup += !seen.insert(c).second;
  }
  return dup;
}

TEST(Coarsen, SphereLosesTrianglesAndGainsQuality) {
  const ImageGrid g = generate::spherical_distance(64);
  const SurfaceMesh fine = generate::contour(g, options(30.5, false));
  generate::ContourStats st;
  const SurfaceMesh coarse = generate::contour(g, options(30.5, true, generate::ContourNormals::Average), &st);
  EXPECT_EQ(st.triangles_before_coarsening, fine.num_cells());
  EXPECT_LT(coarse.num_cells(), fine.num_cells() * 7 / 10);  // a large share goes
  const auto t = analyze::check_topology(coarse);
  EXPECT_EQ(t.degenerate_cells, 0);
  EXPECT_EQ(t.duplicate_points, 0);
  EXPECT_EQ(t.unused_points, 0);
  EXPECT_EQ(duplicate_triangles(coarse), 0);
  const auto qf = analyze::quality(fine), qc = analyze::quality(coarse);
  EXPECT_GT(qc.median, qf.median);
  EXPECT_GT(qc.fraction_above_0_6, qf.fraction_above_0_6);
  // Every coarse point is the mean of fine points near one grid point: within
  // half a voxel diagonal of it, and on the sphere to within a voxel.
  for (Id p = 0; p < coarse.num_points(); ++p) {
    const double x = coarse.points[3 * p] - 32, y = coarse.points[3 * p + 1] - 32, z = coarse.points[3 * p + 2] - 32;
    ASSERT_NEAR(std::sqrt(x * x + y * y + z * z), 30.5, 1.0);
  }
  ASSERT_NE(coarse.find_point_field("Normals"), nullptr);
  ASSERT_NE(coarse.find_point_field("distance"), nullptr);
}

TEST(Coarsen, SameAtAnyThreadCountAndOnTets) {
  const ImageGrid g = generate::spherical_distance(40);
  parallel::set_thread_count(1);
  const SurfaceMesh a = generate::contour(g, options(18.3, true, generate::ContourNormals::Average));
  parallel::set_thread_count(4);
  const SurfaceMesh b = generate::contour(g, options(18.3, true, generate::ContourNormals::Average));
  const UnstructuredGrid tets = generate::tetrahedralize5(g);
  generate::ContourStats st;
  const SurfaceMesh c = generate::contour(tets, options(18.3, true), &st);
  parallel::set_thread_count(0);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.connectivity, b.connectivity);
  EXPECT_EQ(a.point_fields[1].values, b.point_fields[1].values);
  EXPECT_LT(c.num_cells(), st.triangles_before_coarsening);
  EXPECT_EQ(analyze::check_topology(c).degenerate_cells, 0);
  EXPECT_EQ(duplicate_triangles(c), 0);
}

TEST(Coarsen, MergesByKeyAndDropsCollapsedTriangles) {
  // Two triangles sharing an edge; points 1 and 3 share a key: the second
  // triangle (1, 2, 3) collapses, the first keeps its three points.
  SurfaceMesh m;
  m.points = {0, 0, 0, 1, 0, 0, 0, 1, 0, 3, 0, 0};
  m.connectivity = {0, 1, 2, 1, 3, 2};
  m.point_fields.push_back({"s", 1, {1, 2, 3, 6}});
  generate::CoarsenStats st;
  const SurfaceMesh c = generate::coarsen(m, {10, 11, 12, 11}, 13, &st);
  EXPECT_EQ(st.points_after, 3);
  EXPECT_EQ(st.triangles_after, 1);
  EXPECT_EQ(c.connectivity, (std::vector<PointIndex>{0, 1, 2}));
  EXPECT_FLOAT_EQ(c.points[3], 2.f);          // mean of x = 1 and x = 3
  EXPECT_FLOAT_EQ(c.point_fields[0].values[1], 4.f);  // mean of 2 and 6
}

}  // namespace
