#include "keymesh/analyze/self_intersections.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "analyze/triangle_crossing.hpp"
#include "keymesh/analyze/exact_predicates.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/parallel/threads.hpp"

using namespace keymesh;
using analyze::find_self_intersections;
using analyze::triangles_cross;

namespace {

using P = std::array<float, 3>;

bool cross(const std::array<P, 3>& a, const std::array<P, 3>& b) {
  return triangles_cross({a[0].data(), a[1].data(), a[2].data()}, {b[0].data(), b[1].data(), b[2].data()});
}

SurfaceMesh soup(const std::vector<std::array<P, 3>>& tris) {
  SurfaceMesh m;
  m.points.resize(9 * tris.size());
  m.connectivity.resize(3 * tris.size());
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) m.points[9 * t + 3 * k + c] = tris[t][k][c];
      m.connectivity[3 * t + k] = static_cast<PointIndex>(3 * t + k);
    }
  return m;
}

}  // namespace

TEST(ExactPredicates, SignsWhereDoubleRoundingWouldGuess) {
  const P a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  EXPECT_EQ(analyze::orient3d(a.data(), b.data(), c.data(), P{0.3f, 0.7f, 0}.data()), 0);
  EXPECT_EQ(analyze::orient3d(a.data(), b.data(), c.data(), P{0.3f, 0.7f, 1e-30f}.data()), 1);
  EXPECT_EQ(analyze::orient3d(a.data(), b.data(), c.data(), P{0.3f, 0.7f, -1e-30f}.data()), -1);
  // Far from the origin, on a plane x + y + z = const through float points:
  // exactly coplanar, and one ulp off it.
  const float big = 16777216.0f;  // 2^24: floats step by 2 here
  const P p{big, 0, 0}, q{0, big, 0}, r{0, 0, big};
  EXPECT_EQ(analyze::orient3d(p.data(), q.data(), r.data(), P{big / 2, big / 2, 0}.data()), 0);
  const int above = analyze::orient3d(p.data(), q.data(), r.data(), P{big / 2, big / 2, 2.0f}.data());
  EXPECT_NE(above, 0);
  EXPECT_EQ(analyze::orient3d(p.data(), q.data(), r.data(), P{big / 2, big / 2, -2.0f}.data()), -above);
  // Exponents too far apart for 128-bit integers: GMP decides.
  EXPECT_EQ(analyze::orient3d(P{0, 0, 0}.data(), P{1e30f, 0, 0}.data(), P{0, 1e-30f, 0}.data(), P{1, 1, 1e-38f}.data()), 1);
  EXPECT_EQ(analyze::orient2d(P{0, 0, 0}.data(), P{1e30f, 1e-30f, 0}.data(), P{2e30f, 2e-30f, 0}.data(), 2), 0);
  EXPECT_EQ(analyze::orient2d(P{0, 0, 0}.data(), P{1e30f, 1e-30f, 0}.data(), P{2e30f, 3e-30f, 0}.data(), 2), 1);
}

TEST(TrianglesCross, EveryKindOfContact) {
  const std::array<P, 3> base{P{0, 0, 0}, P{4, 0, 0}, P{0, 4, 0}};
  // Pierced through its interior.
  EXPECT_TRUE(cross(base, {P{1, 1, -1}, P{1, 1, 1}, P{3, 3, 1}}));
  // Above it: nothing.
  EXPECT_FALSE(cross(base, {P{1, 1, 0.5f}, P{1, 2, 1}, P{2, 1, 1}}));
  // A common corner (by position only: the soup has other point ids), else apart.
  EXPECT_FALSE(cross(base, {P{0, 0, 0}, P{-1, 0, 1}, P{0, -1, 1}}));
  // A common edge, the other corner above or below: a fold-free hinge.
  EXPECT_FALSE(cross(base, {P{4, 0, 0}, P{0, 0, 0}, P{1, -1, 3}}));
  EXPECT_FALSE(cross(base, {P{4, 0, 0}, P{0, 0, 0}, P{1, 1, 3}}));
  // A common edge, folded flat onto it: overlap.
  EXPECT_TRUE(cross(base, {P{4, 0, 0}, P{0, 0, 0}, P{1, 1, 0}}));
  // A common edge, flat, on the other side: a plain neighbour.
  EXPECT_FALSE(cross(base, {P{4, 0, 0}, P{0, 0, 0}, P{1, -1, 0}}));
  // A corner touching the interior (no common corner): a contact.
  EXPECT_TRUE(cross(base, {P{1, 1, 0}, P{1, 1, 2}, P{2, 1, 2}}));
  // A common corner and an edge running inside the other triangle.
  EXPECT_TRUE(cross(base, {P{0, 0, 0}, P{2, 1, 0}, P{1, 1, 3}}));
  // The same triangle twice, reversed.
  EXPECT_TRUE(cross(base, {P{0, 4, 0}, P{4, 0, 0}, P{0, 0, 0}}));
  // Coplanar, corners apart, edges crossing (a star of David).
  EXPECT_TRUE(cross({P{0, 0, 0}, P{6, 0, 0}, P{3, 5, 0}}, {P{0, 3, 0}, P{6, 3, 0}, P{3, -2, 0}}));
  // An edge of one lying along an edge of the other past their common corner.
  EXPECT_TRUE(cross(base, {P{0, 0, 0}, P{2, 0, 0}, P{1, -1, 2}}));
  // Two triangles of a unit square split both ways (samples on the isovalue do this).
  EXPECT_TRUE(cross({P{0, 0, 0}, P{1, 0, 0}, P{1, 1, 0}}, {P{0, 0, 0}, P{1, 0, 0}, P{0, 1, 0}}));
}

// One common corner (fan neighbours): when one triangle's other two corners
// lie strictly on one side of the other's plane the test ends there, and
// must still tell a real crossing from a touch at the corner.
TEST(TrianglesCross, OneCommonCornerDecidedBySides) {
  const std::array<P, 3> base{P{0, 0, 0}, P{4, 0, 0}, P{0, 4, 0}};
  // Above the base, right over its interior: only the corner in common.
  EXPECT_FALSE(cross(base, {P{0, 0, 0}, P{1, 1, 1}, P{2, 1, 1}}));
  // The far edge pierces the base's interior: a crossing.
  EXPECT_TRUE(cross(base, {P{0, 0, 0}, P{1, 1, -1}, P{1, 1, 1}}));
  // The far edge pierces the base's interior farther out: a crossing too.
  EXPECT_TRUE(cross(base, {P{0, 0, 0}, P{3, 3, -1}, P{3, 3, 1}}));
  // Each straddles the other's plane, but they meet that line on opposite
  // sides of the common corner: apart.
  EXPECT_FALSE(cross(base, {P{0, 0, 0}, P{-1, -1, -1}, P{-1, -1, 1}}));
  // It straddles the base's plane, but the base's other corners lie on one
  // side of its plane (x + y = 0): apart, decided from the base's side.
  EXPECT_FALSE(cross(base, {P{0, 0, 0}, P{-1, 1, 1}, P{-2, 2, -1}}));
  EXPECT_FALSE(cross({P{0, 0, 0}, P{-1, 1, 1}, P{-2, 2, -1}}, base));
}

TEST(SelfIntersections, ClosedSphereHasNoneAndAPlantedTriangleIsFound) {
  const ImageGrid g = generate::spherical_distance(24);
  generate::ContourOptions opt;
  opt.isovalues = {8.3};
  SurfaceMesh m = generate::contour(g, opt);
  const auto clean = find_self_intersections(m);
  EXPECT_EQ(clean.self_intersections, 0);
  EXPECT_EQ(clean.triangles, m.num_cells());
  // A spike from the centre out through the surface crosses exactly the
  // triangles its edges pass through.
  const Id n = m.num_points();
  const std::array<float, 3> centre{11.5f, 11.5f, 11.5f};
  for (float v : {centre[0], centre[1], centre[2], centre[0] + 20, centre[1] + 0.3f, centre[2] + 0.1f,
                  centre[0] + 20, centre[1] + 0.6f, centre[2] + 0.5f})
    m.points.push_back(v);
  for (Id k = 0; k < 3; ++k) m.connectivity.push_back(static_cast<PointIndex>(n + k));
  const auto planted = find_self_intersections(m);
  EXPECT_GE(planted.self_intersections, 1);
  for (const auto& pair : planted.pairs) EXPECT_EQ(pair[1], m.num_cells() - 1);
}

namespace {

bool has_area(const std::array<P, 3>& t) { return analyze::triangle_has_area({t[0].data(), t[1].data(), t[2].data()}); }

// Every pair of a soup's triangles with area that cross, by the public pair
// test alone.
std::vector<std::array<Id, 2>> every_crossing_pair(const std::vector<std::array<P, 3>>& tris) {
  std::vector<std::array<Id, 2>> out;
  for (std::size_t a = 0; a < tris.size(); ++a)
    for (std::size_t b = a + 1; b < tris.size(); ++b)
      if (has_area(tris[a]) && has_area(tris[b]) && cross(tris[a], tris[b])) out.push_back({Id(a), Id(b)});
  return out;
}

// Both broad phases, at several thread counts, find what testing every pair finds.
void expect_every_broad_phase_finds(const SurfaceMesh& m, const std::vector<std::array<Id, 2>>& brute) {
  for (const auto broad : {analyze::BroadPhase::automatic, analyze::BroadPhase::sweep, analyze::BroadPhase::grid})
    for (int threads : {1, 2, 5}) {
      parallel::set_thread_count(threads);
      const auto r = find_self_intersections(m, brute.size(), broad);
      EXPECT_EQ(r.self_intersections, static_cast<Id>(brute.size())) << threads << " " << static_cast<int>(broad);
      EXPECT_EQ(r.pairs, brute) << threads << " " << static_cast<int>(broad);
    }
  parallel::set_thread_count(0);
}

std::vector<std::array<P, 3>> random_soup(std::uint32_t seed, int count, float extent, float size) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> at(0, extent), step(-size, size);
  std::vector<std::array<P, 3>> tris(static_cast<std::size_t>(count));
  for (auto& t : tris) {
    const P o{at(rng), at(rng), at(rng)};
    t = {o, P{o[0] + step(rng), o[1] + step(rng), o[2] + step(rng)}, P{o[0] + step(rng), o[1] + step(rng), o[2] + step(rng)}};
  }
  return tris;
}

// The corners of an integer soup rounded: many coincident corners,
// coplanar and collinear triangles, as a quantized mesh has.
std::vector<std::array<P, 3>> rounded(std::vector<std::array<P, 3>> tris, float offset) {
  for (auto& t : tris)
    for (auto& p : t)
      for (float& c : p) c = std::round(c) + offset;
  return tris;
}

}  // namespace

TEST(SelfIntersections, EveryBroadPhaseEqualsEveryPairOnARandomSoup) {
  std::vector<std::array<P, 3>> tris = random_soup(7, 600, 10, 1.5f);
  tris.push_back(tris[5]);                               // a duplicate
  tris.push_back({tris[9][0], tris[9][1], P{20, 20, 20}});  // a neighbour by an edge's positions
  const auto brute = every_crossing_pair(tris);
  ASSERT_GT(brute.size(), 50u);
  expect_every_broad_phase_finds(soup(tris), brute);
}

// Integer corners (a quantized mesh's) are judged with integer planes:
// the same pairs as orient3d finds, degenerate contacts included, up to
// the bound 2^19 and past it (where orient3d judges again).
TEST(SelfIntersections, IntegerCornersEqualEveryPair) {
  for (const float offset : {0.0f, 524288.0f - 16, -524288.0f + 16, 524288.0f + 16, 0.5f}) {
    const auto tris = rounded(random_soup(11, 700, 8, 2.5f), offset);
    const auto brute = every_crossing_pair(tris);
    ASSERT_GT(brute.size(), 200u) << offset;
    std::size_t coplanar = 0;  // a crossing in one plane
    for (const auto& p : brute) {
      const auto& a = tris[static_cast<std::size_t>(p[0])];
      const auto& b = tris[static_cast<std::size_t>(p[1])];
      coplanar += analyze::orient3d(a[0].data(), a[1].data(), a[2].data(), b[0].data()) == 0 &&
                  analyze::orient3d(a[0].data(), a[1].data(), a[2].data(), b[1].data()) == 0 &&
                  analyze::orient3d(a[0].data(), a[1].data(), a[2].data(), b[2].data()) == 0;
    }
    EXPECT_GT(coplanar, 5u) << offset;
    expect_every_broad_phase_finds(soup(tris), brute);
  }
}

// The integer plane's side and orient3d_integer are orient3d's sign, out to
// the bound 2^19 where their products are largest (and they are only used
// within that bound).
TEST(TriangleCrossing, IntegerPlaneSidesEqualOrient3d) {
  const float bound = 524288.0f;
  EXPECT_TRUE(analyze::detail::integer_coordinates(std::array<float, 3>{bound, -bound, 0}.data(), 3));
  EXPECT_FALSE(analyze::detail::integer_coordinates(std::array<float, 3>{bound + 1, 0, 0}.data(), 3));
  EXPECT_FALSE(analyze::detail::integer_coordinates(std::array<float, 3>{-bound - 1, 0, 0}.data(), 3));
  EXPECT_FALSE(analyze::detail::integer_coordinates(std::array<float, 3>{3, 0.5f, 0}.data(), 3));
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> any(-524288, 524288), corner(0, 1), inward(0, 3);
  // Anywhere, at the extremes, or a little inside them.
  auto coordinate = [&](int kind) {
    if (kind == 0) return static_cast<float>(any(rng));
    const int extreme = corner(rng) ? 524288 : -524288;
    const int in = kind == 1 ? 0 : inward(rng);
    return static_cast<float>(extreme > 0 ? extreme - in : extreme + in);
  };
  int nonzero = 0, zero = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::array<P, 4> p{};
    for (auto& q : p)
      for (float& c : q) c = coordinate(trial % 3);
    if (trial % 5 == 0) p[3] = p[trial % 3];  // on the plane
    const std::array<const float*, 3> t{p[0].data(), p[1].data(), p[2].data()};
    const int expected = analyze::orient3d(p[0].data(), p[1].data(), p[2].data(), p[3].data());
    EXPECT_EQ(analyze::detail::side(analyze::detail::integer_triangle(t), p[3].data()), expected) << trial;
    EXPECT_EQ(analyze::detail::orient3d_integer(p[0].data(), p[1].data(), p[2].data(), p[3].data()), expected) << trial;
    (expected ? nonzero : zero)++;
  }
  EXPECT_GT(nonzero, 5000);
  EXPECT_GT(zero, 2000);
}

// A welded mesh (corners shared by point id) with integer corners: the
// pairs of the same triangles as a soup.
TEST(SelfIntersections, WeldedIntegerMeshEqualsItsSoup) {
  const ImageGrid g = generate::spherical_distance(20);
  generate::ContourOptions opt;
  opt.isovalues = {7.3};
  SurfaceMesh m = generate::contour(g, opt);
  for (float& c : m.points) c = std::round(c * 2);  // coarse integers: many folds and coincident points
  std::vector<std::array<P, 3>> tris(static_cast<std::size_t>(m.num_cells()));
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) tris[t][k][c] = m.points[3 * m.connectivity[3 * t + k] + c];
  const auto brute = every_crossing_pair(tris);
  ASSERT_GT(brute.size(), 20u);
  expect_every_broad_phase_finds(m, brute);
  EXPECT_EQ(find_self_intersections(soup(tris), brute.size()).pairs, brute);
}

TEST(SelfIntersections, PolygonsZeroAreaAndBadInput) {
  SurfaceMesh quad;  // one non-planar quad: its own fan is not tested against itself
  quad.points = {0, 0, 0, 1, 0, 0, 1, 1, 1, 0, 1, 0};
  quad.connectivity = {0, 1, 2, 3};
  quad.offsets = {0, 4};
  auto r = find_self_intersections(quad);
  EXPECT_EQ(r.triangles, 2);
  EXPECT_EQ(r.self_intersections, 0);
  SurfaceMesh flat = soup({{P{0, 0, 0}, P{1, 1, 1}, P{2, 2, 2}}, {P{0, 0, 0}, P{1, 0, 0}, P{0, 1, 0}}});
  r = find_self_intersections(flat);
  EXPECT_EQ(r.zero_area_triangles, 1);
  EXPECT_EQ(r.self_intersections, 0);
  flat.connectivity[0] = 99;
  EXPECT_THROW(find_self_intersections(flat), InputError);
  flat.connectivity[0] = 0;
  flat.points[4] = std::nanf("");
  EXPECT_THROW(find_self_intersections(flat), InputError);
}
