#include "keymesh/mesh/unused_points.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "keymesh/analyze/topology.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/parallel/threads.hpp"

using namespace keymesh;

namespace {

// Every corner's position and field value: what a removal must not change.
std::vector<float> corner_values(const SurfaceMesh& m) {
  std::vector<float> v;
  for (PointIndex p : m.connectivity) {
    for (int a = 0; a < 3; ++a) v.push_back(m.points[3 * std::size_t{p} + a]);
    for (const Field& f : m.point_fields)
      for (int a = 0; a < f.components; ++a) v.push_back(f.values[std::size_t{p} * f.components + a]);
  }
  return v;
}

}  // namespace

TEST(UnusedPoints, HandMeshKeepsOrderAndFields) {
  SurfaceMesh m;
  for (int p = 0; p < 6; ++p) m.points.insert(m.points.end(), {float(p), float(10 * p), float(100 * p)});
  m.connectivity = {0, 2, 3, 3, 2, 5};
  m.point_fields.push_back({"s", 1, {0, 1, 2, 3, 4, 5}});
  m.point_fields.push_back({"v", 2, {0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5}});
  EXPECT_EQ(remove_unused_points(m), 2);
  EXPECT_EQ(m.connectivity, (Array<PointIndex>{0, 1, 2, 2, 1, 3}));
  EXPECT_EQ(m.points, (Array<float>{0, 0, 0, 2, 20, 200, 3, 30, 300, 5, 50, 500}));
  EXPECT_EQ(m.point_fields[0].values, (Array<float>{0, 2, 3, 5}));
  EXPECT_EQ(m.point_fields[1].values, (Array<float>{0, 0, 2, 2, 3, 3, 5, 5}));
  EXPECT_EQ(remove_unused_points(m), 0);  // nothing left to remove
  SurfaceMesh bad = m;
  bad.connectivity[4] = 4;  // past the last of 4 points
  EXPECT_THROW(remove_unused_points(bad), InputError);
  EXPECT_EQ(bad.num_points(), 4);
}

TEST(UnusedPoints, RandomMeshSameCornersAtAnyThreadCount) {
  std::mt19937 rng(7);
  SurfaceMesh m;
  const Id n = 50000;
  for (Id i = 0; i < 3 * n; ++i) m.points.push_back(std::uniform_real_distribution<float>(-1, 1)(rng));
  m.point_fields.push_back({"s", 1, {}});
  for (Id i = 0; i < n; ++i) m.point_fields[0].values.push_back(float(i));
  // Triangles over a random two thirds of the points.
  for (Id t = 0; t < n / 3; ++t)
    for (int k = 0; k < 3; ++k) m.connectivity.push_back(static_cast<PointIndex>(rng() % n));
  std::vector<bool> used(static_cast<std::size_t>(n), false);
  for (PointIndex p : m.connectivity) used[p] = true;
  Id expected_unused = 0;
  for (bool u : used) expected_unused += !u;
  ASSERT_GT(expected_unused, 0);
  const std::vector<float> before = corner_values(m);
  std::vector<SurfaceMesh> got;
  for (int threads : {1, 2, 3}) {
    parallel::set_thread_count(threads);
    SurfaceMesh c = m;
    EXPECT_EQ(remove_unused_points(c), expected_unused);
    got.push_back(c);
  }
  parallel::set_thread_count(0);
  for (const SurfaceMesh& c : got) {
    EXPECT_EQ(c.connectivity, got[0].connectivity);
    EXPECT_EQ(c.points, got[0].points);
    EXPECT_EQ(c.point_fields[0].values, got[0].point_fields[0].values);
  }
  // Told which points are unused (as split_nonmanifold tells coarsening),
  // remove_points gives the same mesh without the scan.
  std::vector<PointIndex> unused;
  for (Id p = 0; p < n; ++p)
    if (!used[p]) unused.push_back(static_cast<PointIndex>(p));
  for (int threads : {1, 3}) {
    parallel::set_thread_count(threads);
    SurfaceMesh told = m;
    remove_points(told, unused);
    EXPECT_EQ(told.connectivity, got[0].connectivity);
    EXPECT_EQ(told.points, got[0].points);
    EXPECT_EQ(told.point_fields[0].values, got[0].point_fields[0].values);
  }
  parallel::set_thread_count(0);
  SurfaceMesh wrong = m;
  std::swap(unused[0], unused[1]);
  EXPECT_THROW(remove_points(wrong, unused), InputError);
  const SurfaceMesh& c = got[0];
  EXPECT_EQ(c.num_points(), n - expected_unused);
  EXPECT_EQ(corner_values(c), before);
  EXPECT_EQ(analyze::check_topology(c).unused_points, 0);
  // The kept points in their old order: the scalar (the old id) increases.
  for (Id p = 1; p < c.num_points(); ++p) ASSERT_LT(c.point_fields[0].values[p - 1], c.point_fields[0].values[p]);
}
