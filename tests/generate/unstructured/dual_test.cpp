#include "keymesh/generate/unstructured/dual.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "keymesh/analyze/incidence.hpp"
#include "keymesh/analyze/topology.hpp"
#include "keymesh/parallel/threads.hpp"
#include "dual_cases.hpp"

using namespace keymesh;
using keymesh::testing::dual_sphere;
using keymesh::testing::open_grid_and_bowtie;

namespace {

TEST(Dual, ClosedSphereSwapsCountsAndKeepsTopology) {
  const SurfaceMesh m = dual_sphere(32, 13.5);
  const auto tm = analyze::check_topology(m);
  generate::DualStats st;
  const SurfaceMesh d = generate::dual(m, &st);
  EXPECT_EQ(d.num_cells(), m.num_points());   // F* = V
  EXPECT_EQ(d.num_points(), m.num_cells());   // V* = F
  const auto td = analyze::check_topology(d);
  EXPECT_EQ(td.edges, tm.edges);              // E* = E
  EXPECT_EQ(td.euler_characteristic, tm.euler_characteristic);
  EXPECT_TRUE(td.closed_manifold);
  EXPECT_EQ(st.boundary_fans + st.nonmanifold_points + st.skipped_fans, 0);
  // Polygon p has as many points as point p has triangles, and turns with them:
  // its normal (Newell) agrees with the averaged normal at p.
  const auto pc = analyze::point_cells(m);
  const Field* n = m.find_point_field("Normals");
  for (Id p = 0; p < m.num_points(); ++p) {
    ASSERT_EQ(Id(d.cell_end(p) - d.cell_begin(p)), pc.count(p));
    double nn[3] = {0, 0, 0};
    for (std::uint64_t k = d.cell_begin(p); k < d.cell_end(p); ++k) {
      const float* a = &d.points[3 * d.connectivity[k]];
      const float* b = &d.points[3 * d.connectivity[k + 1 < d.cell_end(p) ? k + 1 : d.cell_begin(p)]];
      nn[0] += (a[1] - b[1]) * (a[2] + b[2]);
      nn[1] += (a[2] - b[2]) * (a[0] + b[0]);
      nn[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    ASSERT_GT(nn[0] * n->values[3 * p] + nn[1] * n->values[3 * p + 1] + nn[2] * n->values[3 * p + 2], 0) << p;
  }
  // Fields survive (the curvature stays near 1/r).
  const Field* k = d.find_point_field("mean_curvature");
  ASSERT_NE(k, nullptr);
  EXPECT_NEAR(k->values[0], 1 / 13.5, 0.1 / 13.5);
  // The dual of the dual has the input's counts.
  const SurfaceMesh dd = generate::dual(d);
  EXPECT_EQ(dd.num_points(), m.num_points());
  EXPECT_EQ(dd.num_cells(), m.num_cells());
  EXPECT_TRUE(analyze::check_topology(dd).closed_manifold);
}

TEST(Dual, SameAtAnyThreadCount) {
  const SurfaceMesh m = dual_sphere(24, 9.5);
  parallel::set_thread_count(1);
  const SurfaceMesh a = generate::dual(m);
  parallel::set_thread_count(4);
  const SurfaceMesh b = generate::dual(m);
  parallel::set_thread_count(0);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.connectivity, b.connectivity);
  EXPECT_EQ(a.offsets, b.offsets);
}

TEST(Dual, BoundaryAndNonManifoldPointsGiveNoDegeneratePolygon) {
  const SurfaceMesh m = open_grid_and_bowtie();
  generate::DualStats st;
  const SurfaceMesh d = generate::dual(m, &st);
  EXPECT_GE(st.nonmanifold_points, 1);
  EXPECT_GT(st.boundary_fans, 0);
  for (Id c = 0; c < d.num_cells(); ++c) ASSERT_GE(d.cell_end(c) - d.cell_begin(c), 3u);
  const auto t = analyze::check_topology(d);
  EXPECT_EQ(t.degenerate_cells, 0);
  // The centre point 4 is interior: its polygon has its 6 triangles' centroids.
  bool found = false;
  for (Id c = 0; c < d.num_cells(); ++c) found = found || d.cell_end(c) - d.cell_begin(c) == 6;
  EXPECT_TRUE(found);
}

TEST(Incidence, NeighboursAcrossEdges) {
  const SurfaceMesh m = dual_sphere(16, 5.5);
  const auto across = analyze::cell_neighbours(m);
  for (Id t = 0; t < m.num_cells(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::int64_t u = across[3 * t + k];
      ASSERT_GE(u, 0);
      // The neighbour lists t back across the same edge.
      bool back = false;
      for (int j = 0; j < 3; ++j) back = back || across[3 * u + j] == t;
      ASSERT_TRUE(back);
    }
}

}  // namespace
