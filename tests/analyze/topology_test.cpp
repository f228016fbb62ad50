#include "keymesh/analyze/topology.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <set>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/threads.hpp"

using namespace keymesh;
using analyze::check_fans;
using analyze::check_topology;
using analyze::TopologyReport;

namespace {

SurfaceMesh make_mesh(Array<float> pts, Array<PointIndex> conn, Array<std::uint64_t> offsets = {}) {
  SurfaceMesh m;
  m.points = std::move(pts);
  m.connectivity = std::move(conn);
  m.offsets = std::move(offsets);
  return m;
}

SurfaceMesh tetrahedron() {
  return make_mesh({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3});
}

SurfaceMesh octahedron() {
  // +x -x +y -y +z -z
  SurfaceMesh m = make_mesh({1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1}, {});
  const PointIndex xs[2] = {0, 1}, ys[2] = {2, 3}, zs[2] = {4, 5};
  for (PointIndex x : xs)
    for (PointIndex y : ys)
      for (PointIndex z : zs) m.connectivity.insert(m.connectivity.end(), {x, y, z});
  return m;
}

Array<float> cube_points() {
  Array<float> p;
  for (int i = 0; i < 8; ++i) p.insert(p.end(), {float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)});
  return p;
}

// The six faces of the unit cube as quads (point i = (i&1, i>>1&1, i>>2&1)).
const Array<PointIndex> kCubeQuads = {0, 2, 3, 1, 4, 5, 7, 6, 0, 1, 5, 4, 2, 6, 7, 3, 0, 4, 6, 2, 1, 3, 7, 5};

SurfaceMesh cube_triangles() {
  SurfaceMesh m = make_mesh(cube_points(), {});
  for (int f = 0; f < 6; ++f) {
    const PointIndex* q = &kCubeQuads[4 * f];
    m.connectivity.insert(m.connectivity.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  }
  return m;
}

SurfaceMesh torus(int nu, int nv) {
  SurfaceMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * std::numbers::pi * i / nu, v = 2 * std::numbers::pi * j / nv;
      m.points.insert(m.points.end(), {float((3 + std::cos(v)) * std::cos(u)), float((3 + std::cos(v)) * std::sin(u)),
                                       float(std::sin(v))});
    }
  auto id = [&](int i, int j) { return PointIndex((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j)
      m.connectivity.insert(m.connectivity.end(),
                            {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)});
  return m;
}

void expect_closed(const TopologyReport& r, Id chi) {
  EXPECT_TRUE(r.closed_manifold);
  EXPECT_EQ(r.boundary_edges, 0);
  EXPECT_EQ(r.nonmanifold_edges, 0);
  EXPECT_EQ(r.nonmanifold_vertices, 0);
  EXPECT_EQ(r.degenerate_cells, 0);
  EXPECT_EQ(r.euler_characteristic, chi);
  EXPECT_EQ(r.components, 1);
}


}  // namespace

TEST(TopologyTest, Tetrahedron) {
  const auto r = check_topology(tetrahedron());
  EXPECT_EQ(r.points, 4);
  EXPECT_EQ(r.cells, 4);
  EXPECT_EQ(r.edges, 6);
  expect_closed(r, 2);
}

TEST(TopologyTest, Octahedron) {
  const auto r = check_topology(octahedron());
  EXPECT_EQ(r.edges, 12);
  expect_closed(r, 2);
}

TEST(TopologyTest, CubeOfTwelveTriangles) {
  const auto r = check_topology(cube_triangles());
  EXPECT_EQ(r.cells, 12);
  EXPECT_EQ(r.edges, 18);
  expect_closed(r, 2);
}

TEST(TopologyTest, CubeOfSixQuads) {
  const auto r = check_topology(make_mesh(cube_points(), kCubeQuads, {0, 4, 8, 12, 16, 20, 24}));
  EXPECT_EQ(r.cells, 6);
  EXPECT_EQ(r.edges, 12);
  expect_closed(r, 2);
}

TEST(TopologyTest, Torus) {
  const auto r = check_topology(torus(12, 8));
  EXPECT_EQ(r.points, 96);
  EXPECT_EQ(r.edges, 3 * 96);
  EXPECT_EQ(r.duplicate_points, 0);
  expect_closed(r, 0);
}

TEST(TopologyTest, SingleTriangle) {
  const auto r = check_topology(make_mesh({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2}));
  EXPECT_EQ(r.edges, 3);
  EXPECT_EQ(r.boundary_edges, 3);
  EXPECT_EQ(r.nonmanifold_vertices, 0);  // a single open fan at each corner is manifold
  EXPECT_EQ(r.euler_characteristic, 1);
  EXPECT_EQ(r.components, 1);
  EXPECT_FALSE(r.closed_manifold);
}

TEST(TopologyTest, TwoTetrahedraSharingOneVertex) {
  SurfaceMesh m = tetrahedron();
  // Second tetrahedron: point 0 shared, points 4..6 new, mirrored through the origin.
  m.points.insert(m.points.end(), {-1, 0, 0, 0, -1, 0, 0, 0, -1});
  m.connectivity.insert(m.connectivity.end(), {0, 4, 5, 0, 6, 4, 0, 5, 6, 4, 6, 5});
  const auto r = check_topology(m);
  EXPECT_EQ(r.points, 7);
  EXPECT_EQ(r.edges, 12);
  EXPECT_EQ(r.boundary_edges, 0);
  EXPECT_EQ(r.nonmanifold_edges, 0);
  EXPECT_EQ(r.nonmanifold_vertices, 1);
  EXPECT_EQ(r.components, 1);
  EXPECT_EQ(r.euler_characteristic, 7 - 12 + 8);
  EXPECT_FALSE(r.closed_manifold);
}

TEST(TopologyTest, ThreeTrianglesOnOneEdge) {
  const auto r = check_topology(
      make_mesh({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1}, {0, 1, 2, 1, 0, 3, 0, 1, 4}));
  EXPECT_EQ(r.edges, 7);
  EXPECT_EQ(r.nonmanifold_edges, 1);
  EXPECT_EQ(r.boundary_edges, 6);
  EXPECT_EQ(r.nonmanifold_vertices, 0);  // the fans are joined through the shared edge
  EXPECT_EQ(r.euler_characteristic, 5 - 7 + 3);
  EXPECT_FALSE(r.closed_manifold);
}

TEST(TopologyTest, DuplicateAndUnusedPoints) {
  SurfaceMesh m = tetrahedron();
  m.points.insert(m.points.end(), {0, 0, 0});       // same position as point 0, unused
  m.points.insert(m.points.end(), {5, 5, 5});       // unused
  m.points.insert(m.points.end(), {-0.0f, 0, 0});   // -0 == +0: another duplicate of point 0
  const auto r = check_topology(m);
  EXPECT_EQ(r.points, 7);
  EXPECT_EQ(r.duplicate_points, 2);
  EXPECT_EQ(r.unused_points, 3);
  expect_closed(r, 2);  // unused points do not count in V
}

TEST(TopologyTest, DegenerateCell) {
  SurfaceMesh m = make_mesh({0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5, 6, 5, 5}, {0, 1, 2, 3, 3, 4});
  const auto r = check_topology(m);
  EXPECT_EQ(r.degenerate_cells, 1);
  EXPECT_EQ(r.components, 2);
  EXPECT_FALSE(r.closed_manifold);
  // A polygon that revisits a point is degenerate too.
  SurfaceMesh p = make_mesh({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 0, 2}, {0, 4});
  EXPECT_EQ(check_topology(p).degenerate_cells, 1);
}

TEST(TopologyTest, OutOfRangeIdThrows) {
  SurfaceMesh m = tetrahedron();
  m.connectivity[5] = 4;
  EXPECT_THROW(check_topology(m), InputError);
  SurfaceMesh bad_offsets = make_mesh(cube_points(), kCubeQuads, {0, 4, 8, 12, 16, 20, 25});
  EXPECT_THROW(check_topology(bad_offsets), InputError);
}

TEST(TopologyTest, EmptyMesh) {
  const auto r = check_topology(SurfaceMesh{});
  EXPECT_EQ(r.cells, 0);
  EXPECT_EQ(r.components, 0);
  EXPECT_FALSE(r.closed_manifold);
}

TEST(TopologyTest, TwoComponentsOpenBoundary) {
  SurfaceMesh m = torus(6, 5);
  const Id tris = m.num_cells();
  m.connectivity.resize(3 * (tris - 1));  // punch one hole: 3 boundary edges
  SurfaceMesh t = tetrahedron();
  const auto base = PointIndex(m.num_points());
  m.points.insert(m.points.end(), t.points.begin(), t.points.end());
  for (PointIndex id : t.connectivity) m.connectivity.push_back(id + base);
  const auto r = check_topology(m);
  EXPECT_EQ(r.components, 2);
  EXPECT_EQ(r.boundary_edges, 3);
  EXPECT_EQ(r.nonmanifold_vertices, 0);
  EXPECT_EQ(r.euler_characteristic, (0 - 1) + 2);
}

// Performance is measured by benchmarks, not here: this checks a large mesh
// gives exact counts and the same report at 1 and N threads.
TEST(TopologyTest, LargeTorusIsExactAndDeterministic) {
  const SurfaceMesh m = torus(1000, 1500);  // 3 million triangles
  const int saved = parallel::thread_count();
  const auto r = check_topology(m);
  EXPECT_EQ(r.edges, 3 * 1000 * 1500);
  expect_closed(r, 0);
  parallel::set_thread_count(1);
  const auto r1 = check_topology(m);
  parallel::set_thread_count(saved);
  EXPECT_EQ(r1.edges, r.edges);
  EXPECT_EQ(r1.components, r.components);
  EXPECT_EQ(r1.duplicate_points, r.duplicate_points);
  EXPECT_EQ(r1.nonmanifold_vertices, r.nonmanifold_vertices);
}

// check_fans gives check_topology's edge and vertex counts on meshes with
// every kind of defect (the coarsened contour's report reads it), and
// leaves the rest unset.
TEST(TopologyTest, CheckFansCountsAsCheckTopology) {
  SurfaceMesh pinched = tetrahedron();
  pinched.points.insert(pinched.points.end(), {-1, 0, 0, 0, -1, 0, 0, 0, -1, 5, 5, 5});
  pinched.connectivity.insert(pinched.connectivity.end(), {0, 4, 5, 0, 6, 4, 0, 5, 6, 4, 6, 5, 1, 1, 2});
  const SurfaceMesh meshes[] = {tetrahedron(), cube_triangles(), torus(7, 5), pinched,
                                make_mesh({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1}, {0, 1, 2, 1, 0, 3, 0, 1, 4})};
  for (const SurfaceMesh& m : meshes) {
    const TopologyReport all = check_topology(m), fans = check_fans(m);
    for (Id TopologyReport::*count : {&TopologyReport::points, &TopologyReport::cells, &TopologyReport::edges,
                                      &TopologyReport::boundary_edges, &TopologyReport::nonmanifold_edges,
                                      &TopologyReport::nonmanifold_vertices, &TopologyReport::unused_points,
                                      &TopologyReport::degenerate_cells})
      EXPECT_EQ(fans.*count, all.*count);
    EXPECT_EQ(fans.components, 0);
    EXPECT_FALSE(fans.closed_manifold);
  }
  EXPECT_EQ(check_fans(meshes[3]).nonmanifold_vertices, 1);
  EXPECT_EQ(check_fans(meshes[3]).unused_points, 1);
  EXPECT_EQ(check_fans(meshes[4]).nonmanifold_edges, 1);
}

// The triangle meshes' fast path (bit masks of the corners holding each
// point) against the general one, which a triangle mesh given with
// explicit cell offsets takes: random meshes over few points, so that every
// defect occurs (edges of one, two, three and more cells, pinched vertices,
// triangles repeating a point, unused points), and points of more than 64
// corners (the fast path's limit) as well.
TEST(TopologyTest, TriangleFastPathCountsAsThePolygonPath) {
  std::uint64_t state = 12345;
  auto next_random = [&](std::uint64_t n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return (state >> 33) % n;
  };
  int meshes_with[4] = {};  // boundary, non-manifold edges, non-manifold vertices, degenerate cells
  for (int trial = 0; trial < 300; ++trial) {
    const std::uint64_t points = 4 + next_random(trial < 200 ? 40 : 8), triangles = 1 + next_random(trial < 200 ? 60 : 200);
    SurfaceMesh tri;
    tri.points.assign(3 * points, 0.0f);
    for (std::uint64_t t = 0; t < triangles; ++t) {
      const auto a = static_cast<PointIndex>(next_random(points));
      auto b = static_cast<PointIndex>(next_random(points)), c = static_cast<PointIndex>(next_random(points));
      if (next_random(8) != 0) {  // mostly proper triangles
        while (b == a) b = static_cast<PointIndex>(next_random(points));
        while (c == a || c == b) c = static_cast<PointIndex>(next_random(points));
      }
      tri.connectivity.insert(tri.connectivity.end(), {a, b, c});
    }
    SurfaceMesh poly = tri;
    for (std::uint64_t t = 0; t <= triangles; ++t) poly.offsets.push_back(3 * t);
    const TopologyReport fast = check_fans(tri), general = check_fans(poly);
    for (Id TopologyReport::*count : {&TopologyReport::edges, &TopologyReport::boundary_edges,
                                      &TopologyReport::nonmanifold_edges, &TopologyReport::nonmanifold_vertices,
                                      &TopologyReport::unused_points, &TopologyReport::degenerate_cells})
      EXPECT_EQ(fast.*count, general.*count) << "trial " << trial;
    meshes_with[0] += fast.boundary_edges > 0, meshes_with[1] += fast.nonmanifold_edges > 0;
    meshes_with[2] += fast.nonmanifold_vertices > 0, meshes_with[3] += fast.degenerate_cells > 0;
  }
  for (int kind = 0; kind < 4; ++kind) EXPECT_GT(meshes_with[kind], 20) << "defect kind " << kind;
  // Points with one or two corners in a triangle repeating a point (whose
  // corners' other points could pass for a cycle), beside a proper one.
  for (const Array<PointIndex>& conn : {Array<PointIndex>{0, 0, 1}, Array<PointIndex>{0, 1, 1}, Array<PointIndex>{1, 0, 0},
                                        Array<PointIndex>{0, 0, 1, 1, 2, 3}, Array<PointIndex>{0, 1, 1, 0, 2, 3}}) {
    const SurfaceMesh tri = make_mesh(Array<float>(12, 0.0f), conn);
    SurfaceMesh poly = tri;
    for (Id t = 0; t <= tri.num_cells(); ++t) poly.offsets.push_back(static_cast<std::uint64_t>(3 * t));
    const TopologyReport fast = check_fans(tri), general = check_fans(poly);
    EXPECT_EQ(fast.boundary_edges, general.boundary_edges);
    EXPECT_EQ(fast.edges, general.edges);
    EXPECT_EQ(fast.degenerate_cells, general.degenerate_cells);
    EXPECT_GT(general.boundary_edges, 0);
  }
  // A closed torus and a fan of 80 triangles around one point (an open disk,
  // then pinched by a second fan at the same point).
  const SurfaceMesh closed = torus(9, 7);
  SurfaceMesh closed_poly = closed;
  for (Id t = 0; t <= closed.num_cells(); ++t) closed_poly.offsets.push_back(static_cast<std::uint64_t>(3 * t));
  EXPECT_EQ(check_fans(closed).edges, check_fans(closed_poly).edges);
  EXPECT_EQ(check_fans(closed).nonmanifold_vertices, 0);
  SurfaceMesh fan;
  fan.points.assign(3 * 162, 0.0f);
  for (PointIndex t = 0; t < 80; ++t) fan.connectivity.insert(fan.connectivity.end(), {0, 1 + t, 2 + t});
  EXPECT_EQ(check_fans(fan).nonmanifold_vertices, 0);
  EXPECT_EQ(check_fans(fan).boundary_edges, 80 + 2);
  for (PointIndex t = 0; t < 3; ++t) fan.connectivity.insert(fan.connectivity.end(), {0, 100 + t, 101 + t});
  EXPECT_EQ(check_fans(fan).nonmanifold_vertices, 1);
}

// duplicate_points against a count made here: the positions (x, y, z with -0
// as +0) in a std::set, NaN points never counted. Points on few grid planes
// (as a contour's), repeated, with -0, NaN and a large run of one position;
// with the default hash bits, and with 1 and 3 bits, which put hundreds of
// positions in each run (the run's sort by coordinates).
TEST(TopologyTest, DuplicatePointsCountAsASetOfPositions) {
  std::mt19937 rng(7);
  for (int round = 0; round < 20; ++round) {
    const Id n = 50 + static_cast<Id>(rng() % 3000);
    std::vector<float> xyz(static_cast<std::size_t>(3 * n));
    for (Id i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) xyz[3 * i + a] = static_cast<float>(static_cast<int>(rng() % 7) - 3) * 0.5f;
      if (rng() % 5 == 0) xyz[3 * i + rng() % 3] = static_cast<float>(rng() % 1000) / 7.0f;
      if (rng() % 17 == 0) xyz[3 * i + rng() % 3] = -0.0f;
      if (rng() % 29 == 0) xyz[3 * i + rng() % 3] = std::numeric_limits<float>::quiet_NaN();
      if (round % 4 == 0 && i % 3 == 0) xyz[3 * i] = xyz[3 * i + 1] = xyz[3 * i + 2] = 1.0f;  // one long run
    }
    std::set<std::array<float, 3>> positions;
    Id expected = 0;
    for (Id i = 0; i < n; ++i) {
      std::array<float, 3> p{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
      if (p[0] != p[0] || p[1] != p[1] || p[2] != p[2]) continue;
      for (float& c : p) c = c == 0.0f ? 0.0f : c;
      if (!positions.insert(p).second) ++expected;
    }
    ASSERT_GT(expected, 0);
    for (int bits : {0, 1, 3})
      EXPECT_EQ(analyze::detail::count_duplicate_points(xyz.data(), n, bits), expected) << "round " << round << " bits " << bits;
  }
}
