// coarsen_part (one part of a mesh coarsened beside others, its split's rounds
// agreed) and check_fans' counts at marked points: what the coarsened
// contour's pieces under mpirun build on (distributed/coarse_pieces.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "keymesh/analyze/topology.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/generate/coarsen/coarsen.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/mesh/unused_points.hpp"

using namespace keymesh;

namespace {

// White noise (inside a border of zeros, or open where it meets the
// volume's sides): pinched points on every side, and points whose every
// triangle collapses.
ImageGrid noise(Id n, unsigned seed, bool zero_border = true) {
  ImageGrid g;
  g.allocate({n, n, n}, ScalarType::Float32);
  std::mt19937 rng(seed);
  auto* v = reinterpret_cast<float*>(g.data());
  for (Id p = 0; p < n * n * n; ++p) {
    const Id i = p % n, j = (p / n) % n, k = p / (n * n);
    const bool border = i == 0 || j == 0 || k == 0 || i == n - 1 || j == n - 1 || k == n - 1;
    const float x = std::uniform_real_distribution<float>(0, 1)(rng);
    v[p] = border && zero_border ? 0.f : x;
  }
  return g;
}

}  // namespace

// A single part whose rounds follow the one-process rule (go on while it
// added a copy and left an edge joined) gives coarsen()'s mesh once its
// unused points are removed, and reports what the split did: the copies'
// sources and rounds, the first round's points, how many rounds ran.
TEST(CoarsenPart, OnePartWithTheWholeMeshsRoundsIsCoarsen) {
  for (unsigned seed : {2u, 5u, 9u}) {
    const ImageGrid g = noise(24, seed);
    generate::ContourOptions o;
    o.isovalues = {0.5};
    o.normals = generate::ContourNormals::None;
    std::vector<std::uint64_t> nearest;
    const SurfaceMesh fine = generate::contour(g, o, nullptr, nullptr, &nearest);
    const auto range = static_cast<std::uint64_t>(g.num_points());
    const SurfaceMesh ref = generate::coarsen(fine, nearest, range);
    int agreements = 0;
    const generate::SplitRounds rounds{[](PointIndex) { return true; }, [&](Id added, Id left) {
                                         ++agreements;
                                         return added > 0 && left > 0;
                                       }};
    generate::NonmanifoldSplit split;
    SurfaceMesh got = generate::coarsen_part(fine, nearest, range, rounds, split);
    ASSERT_GT(split.split_from.size(), 0u) << "seed " << seed << ": nothing split, the test would prove nothing";
    EXPECT_EQ(split.copy_round.size(), split.split_from.size());
    EXPECT_EQ(split.rounds, agreements);
    const Id originals = got.num_points() - static_cast<Id>(split.split_from.size());
    for (std::size_t i = 0; i < split.split_from.size(); ++i) {
      EXPECT_LT(Id{split.split_from[i]}, originals + static_cast<Id>(i));  // an original or an earlier copy
      EXPECT_TRUE(split.copy_round[i] >= 1 && split.copy_round[i] <= split.rounds);
    }
    EXPECT_TRUE(std::is_sorted(split.first_flagged.begin(), split.first_flagged.end()));
    remove_points(got, split.unused);
    EXPECT_EQ(got.points, ref.points) << "seed " << seed;
    EXPECT_EQ(got.connectivity, ref.connectivity) << "seed " << seed;
  }
}

// check_fans at marked points: every point marked gives check_fans' counts;
// marks split in two parts add up to them (each edge counted at its smaller
// end, each vertex at itself).
TEST(CoarsenPart, FanCountsAtMarkedPointsAddUp) {
  const ImageGrid g = noise(20, 4, false);
  generate::ContourOptions o;
  o.isovalues = {0.45};
  o.normals = generate::ContourNormals::None;
  o.coarsen = true;
  const SurfaceMesh m = generate::contour(g, o);
  const auto whole = analyze::check_fans(m);
  ASSERT_GT(whole.boundary_edges, 0);
  const auto n = static_cast<std::size_t>(m.num_points());
  std::vector<std::uint8_t> all(n, 1), low(n, 0), high(n, 0);
  for (std::size_t p = 0; p < n; ++p) (p % 3 ? low : high)[p] = 1;
  const auto a = analyze::check_fans(m, all), l = analyze::check_fans(m, low), h = analyze::check_fans(m, high);
  EXPECT_EQ(a.edges, whole.edges);
  EXPECT_EQ(a.boundary_edges, whole.boundary_edges);
  EXPECT_EQ(a.nonmanifold_edges, whole.nonmanifold_edges);
  EXPECT_EQ(a.nonmanifold_vertices, whole.nonmanifold_vertices);
  EXPECT_EQ(l.edges + h.edges, whole.edges);
  EXPECT_EQ(l.boundary_edges + h.boundary_edges, whole.boundary_edges);
  EXPECT_EQ(l.nonmanifold_edges + h.nonmanifold_edges, whole.nonmanifold_edges);
  EXPECT_EQ(l.nonmanifold_vertices + h.nonmanifold_vertices, whole.nonmanifold_vertices);
  EXPECT_LT(l.edges, whole.edges);
  EXPECT_THROW(analyze::check_fans(m, std::vector<std::uint8_t>(n + 1, 1)), InputError);
}
