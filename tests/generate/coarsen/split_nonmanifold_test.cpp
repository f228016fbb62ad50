#include "keymesh/generate/coarsen/split_nonmanifold.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "keymesh/analyze/topology.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/mesh/unused_points.hpp"
#include "keymesh/parallel/threads.hpp"

using namespace keymesh;

namespace {

// The surface of a tetrahedron on points a, b, c, d (outward when a, b, c
// turn counter-clockwise seen from outside and d is behind them).
Array<PointIndex> tetrahedron(PointIndex a, PointIndex b, PointIndex c, PointIndex d) {
  return {a, c, b, a, b, d, b, c, d, c, a, d};
}

SurfaceMesh points_at_random(Id n) {
  SurfaceMesh m;
  std::mt19937 rng(3);
  for (Id i = 0; i < 3 * n; ++i) m.points.push_back(std::uniform_real_distribution<float>(0, 1)(rng));
  return m;
}

// Whether `out` is `ref` with its points renamed one to one (the triangles in
// the same order): the reference a split must give back when the
// non-manifold points were made by identifying points of `ref`.
bool renamed(const SurfaceMesh& ref, const SurfaceMesh& out) {
  if (ref.connectivity.size() != out.connectivity.size()) return false;
  std::map<PointIndex, PointIndex> to, from;
  for (std::size_t k = 0; k < ref.connectivity.size(); ++k) {
    const PointIndex r = ref.connectivity[k], o = out.connectivity[k];
    if (to.emplace(r, o).first->second != o || from.emplace(o, r).first->second != r) return false;
  }
  return true;
}

TEST(SplitNonmanifold, TwoTetrahedraOnOnePointBecomeTwo) {
  SurfaceMesh m = points_at_random(7);
  m.connectivity = tetrahedron(0, 1, 2, 3);
  const auto second = tetrahedron(0, 4, 5, 6);
  m.connectivity.insert(m.connectivity.end(), second.begin(), second.end());
  m.point_fields.push_back({"s", 1, {0, 1, 2, 3, 4, 5, 6}});
  const SurfaceMesh before = m;
  ASSERT_EQ(analyze::check_topology(m).nonmanifold_vertices, 1);
  m.points.insert(m.points.end(), {9, 9, 9});  // point 7, in no triangle
  m.point_fields[0].values.push_back(7);
  const auto r = generate::split_nonmanifold(m);
  EXPECT_EQ(r.points_added, 1);
  EXPECT_EQ(r.edges_left, 0);
  EXPECT_EQ(r.unused, std::vector<PointIndex>{7});  // left in place, the copy after it
  remove_points(m, r.unused);
  const auto t = analyze::check_topology(m);
  EXPECT_TRUE(t.closed_manifold);
  EXPECT_EQ(t.unused_points, 0);
  EXPECT_EQ(t.components, 2);
  EXPECT_EQ(t.euler_characteristic, 4);  // two spheres
  EXPECT_EQ(t.duplicate_points, 1);      // the copy sits where point 0 sits
  // The first tetrahedron holds point 0's first corner and keeps it; the
  // second's corners there go to the copy, which carries point 0's values.
  for (std::size_t k = 0; k < 12; ++k) EXPECT_EQ(m.connectivity[k], before.connectivity[k]);
  for (std::size_t k = 12; k < 24; ++k)
    EXPECT_EQ(m.connectivity[k], before.connectivity[k] == 0 ? 7u : before.connectivity[k]);
  EXPECT_EQ(std::vector<float>(m.points.begin() + 21, m.points.end()), std::vector<float>(m.points.begin(), m.points.begin() + 3));
  EXPECT_EQ(m.point_fields[0].values.back(), 0.f);
}

// Two tetrahedra sharing edge (0, 1): four triangles on it, two each way.
// Listed so that the first pairing (by triangle order) joins a triangle of
// each, which leaves one fan at both ends: the rotation must separate them.
TEST(SplitNonmanifold, TwoTetrahedraOnOneEdgeBecomeTwo) {
  for (bool crossed : {false, true}) {
    SurfaceMesh m = points_at_random(6);
    const auto a = tetrahedron(0, 1, 2, 3), b = tetrahedron(1, 0, 4, 5);
    // (triangle, from b): a's first triangle runs 1 -> 0, its second 0 -> 1;
    // b's first runs 0 -> 1, its second 1 -> 0. Moving a's first to the end
    // makes the first pairing (a's second, b's second).
    std::vector<std::pair<std::vector<PointIndex>, bool>> tris;
    for (std::size_t t = 0; t < 4; ++t) tris.push_back({{a[3 * t], a[3 * t + 1], a[3 * t + 2]}, false});
    for (std::size_t t = 0; t < 4; ++t) tris.push_back({{b[3 * t], b[3 * t + 1], b[3 * t + 2]}, true});
    if (crossed) std::rotate(tris.begin(), tris.begin() + 1, tris.end());
    for (const auto& t : tris) m.connectivity.insert(m.connectivity.end(), t.first.begin(), t.first.end());
    const SurfaceMesh before = m;
    ASSERT_EQ(analyze::check_topology(m).nonmanifold_edges, 1);
    const auto r = generate::split_nonmanifold(m);
    EXPECT_EQ(r.points_added, 2) << crossed;
    EXPECT_EQ(r.edges_left, 0) << crossed;
    const auto t = analyze::check_topology(m);
    EXPECT_TRUE(t.closed_manifold) << crossed;
    EXPECT_EQ(t.components, 2) << crossed;
    EXPECT_EQ(t.euler_characteristic, 4) << crossed;
    // The reference: the same two tetrahedra on six plus two distinct points.
    SurfaceMesh apart = before;
    for (std::size_t k = 0; k < 24; ++k)
      if (tris[k / 3].second && apart.connectivity[k] < 2) apart.connectivity[k] += 6;
    EXPECT_TRUE(renamed(apart, m)) << crossed;
  }
}

// A corner referring to a point past the last is refused by name, in
// either triangle order (the check sits where such a corner must go), and
// told suspects too; the refused call leaves nothing behind for the next
// (its scratch marks the listed points: a point left marked would be
// gathered, and split, though not listed).
TEST(SplitNonmanifold, RefusesPointsPastTheLast) {
  for (bool last : {false, true}) {
    SurfaceMesh m = points_at_random(4);
    m.connectivity = tetrahedron(0, 1, 2, 3);
    m.connectivity[last ? 11 : 0] = 9;
    EXPECT_THROW(generate::split_nonmanifold(m), InputError) << last;
    EXPECT_THROW(generate::split_nonmanifold(m, {{0, 1, 2, 3}, {}}), InputError) << last;
  }
  // Two tetrahedra touching at point 0 (two fans), told of point 1 only.
  SurfaceMesh m = points_at_random(7);
  m.connectivity = tetrahedron(0, 1, 2, 3);
  for (PointIndex c : tetrahedron(0, 4, 5, 6)) m.connectivity.push_back(c);
  const auto before = m.connectivity;
  EXPECT_EQ(generate::split_nonmanifold(m, {{1}, {}}).points_added, 0);
  EXPECT_EQ(m.connectivity, before);
  EXPECT_EQ(generate::split_nonmanifold(m, {{0}, {}}).points_added, 1);
}

// Told where to look: with every point as a suspect, or only those the
// whole-mesh form finds not one closed fan, the same bytes as that form;
// a list lacking one leaves it unsplit (no crash); an unsorted list, or one
// past the last point, is refused by name.
TEST(SplitNonmanifold, SuspectsGivenSplitAsFound) {
  SurfaceMesh m = points_at_random(10);
  m.connectivity = tetrahedron(0, 1, 2, 3);
  for (const auto& more : {tetrahedron(0, 4, 5, 6), tetrahedron(1, 0, 7, 8), tetrahedron(9, 5, 4, 2)})
    m.connectivity.insert(m.connectivity.end(), more.begin(), more.end());
  m.point_fields.push_back({"s", 1, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9}});
  const auto before = analyze::check_topology(m);
  ASSERT_GT(before.nonmanifold_vertices + before.nonmanifold_edges, 0);
  SurfaceMesh whole = m;
  const auto expected = generate::split_nonmanifold(whole);
  ASSERT_GT(expected.points_added, 0);
  // The odd points: those whose fans the whole-mesh form changed, or whose
  // copies it made (their corners moved to new ids).
  std::set<PointIndex> odd;
  for (std::size_t k = 0; k < m.connectivity.size(); ++k)
    if (whole.connectivity[k] != m.connectivity[k]) odd.insert(m.connectivity[k]);
  std::vector<PointIndex> all(10);
  for (PointIndex p = 0; p < 10; ++p) all[p] = p;
  // The four tetrahedra's triangles in two ranges: 0-7 and 8-15.
  const std::vector<generate::TriangleRange> halves{{0, 8}, {8, 16}};
  for (const auto& suspects : {generate::NonmanifoldSuspects{all, {}},
                               generate::NonmanifoldSuspects{std::vector<PointIndex>(odd.begin(), odd.end()), halves}}) {
    SurfaceMesh told = m;
    const auto r = generate::split_nonmanifold(told, suspects);
    EXPECT_EQ(r.points_added, expected.points_added);
    EXPECT_EQ(r.edges_left, expected.edges_left);
    EXPECT_EQ(told.connectivity, whole.connectivity);
    EXPECT_EQ(told.points, whole.points);
    EXPECT_EQ(told.point_fields[0].values, whole.point_fields[0].values);
  }
  SurfaceMesh partial = m;
  const auto r = generate::split_nonmanifold(partial, {{*odd.begin()}, {}});
  EXPECT_LE(r.points_added, expected.points_added);
  SurfaceMesh refused = m;
  EXPECT_THROW(generate::split_nonmanifold(refused, {{3, 1}, {}}), InputError);
  EXPECT_THROW(generate::split_nonmanifold(refused, {{1, 10}, {}}), InputError);
  EXPECT_THROW(generate::split_nonmanifold(refused, {{1}, {{8, 16}, {0, 8}}}), InputError);
  EXPECT_THROW(generate::split_nonmanifold(refused, {{1}, {{0, 17}}}), InputError);
}

// A bipyramid: apex `top`, `d` equator points from `first` on, apex
// `bottom`; closed, every point one fan (the apexes of degree d).
Array<PointIndex> bipyramid(PointIndex top, PointIndex bottom, PointIndex first, PointIndex d) {
  Array<PointIndex> t;
  for (PointIndex k = 0; k < d; ++k) {
    const PointIndex a = first + k, b = first + (k + 1) % d;
    t.insert(t.end(), {top, a, b, bottom, b, a});
  }
  return t;
}

// A point of every degree from 3 to 20, and of 64 to 81 (the fan check has
// a path up to 8 corners and another above; the rule compares ends up to 64
// corners and sorts them above): one bipyramid's apex is one fan; two
// bipyramids sharing their top apex make it a point of two fans (degree
// d1 + d2), split into exactly one copy: the two bipyramids apart, renamed.
// Also with the triangles shuffled, so that no corner's ends come in order.
TEST(SplitNonmanifold, FansOfEveryDegree) {
  std::mt19937 rng(13);
  for (PointIndex d1 : {3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 32, 40}) {
    SurfaceMesh one = points_at_random(d1 + 2);
    one.connectivity = bipyramid(0, 1, 2, d1);
    ASSERT_TRUE(analyze::check_topology(one).closed_manifold);
    EXPECT_EQ(generate::split_nonmanifold(one).points_added, 0) << d1;
    for (PointIndex d2 : d1 < 32 ? std::vector<PointIndex>{3, 5, 8} : std::vector<PointIndex>{32, 41})
      for (bool shuffle : {false, true}) {
        SurfaceMesh two = points_at_random(d1 + d2 + 3);
        two.connectivity = bipyramid(0, 1, 2, d1);
        SurfaceMesh apart = two;
        const auto second = bipyramid(0, 2 + d1, 3 + d1, d2);
        two.connectivity.insert(two.connectivity.end(), second.begin(), second.end());
        const auto second_apart = bipyramid(d1 + d2 + 3, 2 + d1, 3 + d1, d2);
        apart.connectivity.insert(apart.connectivity.end(), second_apart.begin(), second_apart.end());
        if (shuffle) {
          std::vector<std::size_t> order(static_cast<std::size_t>(two.num_cells()));
          for (std::size_t t = 0; t < order.size(); ++t) order[t] = t;
          std::shuffle(order.begin(), order.end(), rng);
          for (SurfaceMesh* m : {&two, &apart}) {
            const Array<PointIndex> c = m->connectivity;
            for (std::size_t t = 0; t < order.size(); ++t)
              for (int k = 0; k < 3; ++k) m->connectivity[3 * t + k] = c[3 * order[t] + k];
          }
        }
        const auto r = generate::split_nonmanifold(two);
        EXPECT_EQ(r.points_added, 1) << d1 << " " << d2 << " " << shuffle;
        EXPECT_TRUE(renamed(apart, two)) << d1 << " " << d2 << " " << shuffle;
        const auto t = analyze::check_topology(two);
        EXPECT_TRUE(t.closed_manifold) << d1 << " " << d2 << " " << shuffle;
        EXPECT_EQ(t.components, 2) << d1 << " " << d2 << " " << shuffle;
      }
  }
}

// A closed 2-manifold: smoothed noise inside a border of low values.
SurfaceMesh closed_noise_surface() {
  ImageGrid g;
  const Id n = 28;
  g.allocate({n, n, n}, ScalarType::Float32);
  std::mt19937 rng(11);
  auto* v = reinterpret_cast<float*>(g.data());
  std::vector<float> w(static_cast<std::size_t>(n * n * n));
  for (float& x : w) x = std::uniform_real_distribution<float>(0, 1)(rng);
  for (int axis = 0; axis < 3; ++axis) {  // a box filter along each axis
    const Id stride = axis == 0 ? 1 : axis == 1 ? n : n * n;
    std::vector<float> s = w;
    for (Id p = 0; p < n * n * n; ++p) {
      const Id i = (p / stride) % n;
      s[p] = (w[p] + w[i > 0 ? p - stride : p] + w[i + 1 < n ? p + stride : p]) / 3;
    }
    w = s;
  }
  for (Id k = 0; k < n; ++k)
    for (Id j = 0; j < n; ++j)
      for (Id i = 0; i < n; ++i) {
        const bool border = i == 0 || j == 0 || k == 0 || i == n - 1 || j == n - 1 || k == n - 1;
        v[i + n * (j + n * k)] = border ? 0.f : w[i + n * (j + n * k)];
      }
  generate::ContourOptions o;
  o.isovalues = {0.5};
  o.normals = generate::ContourNormals::None;
  return generate::contour(g, o);
}

// Points identified in a closed 2-manifold (whole stars two apart, so that
// the rule's fans are exactly the stars): pinches of one point with another,
// and edges laid on other edges the other way round (four triangles on the
// edge, two each way). The split must give back the surface, renamed.
TEST(SplitNonmanifold, UndoesIdentifiedPointsAndEdges) {
  const SurfaceMesh ref = closed_noise_surface();
  const auto topo = analyze::check_topology(ref);
  ASSERT_TRUE(topo.closed_manifold);
  const Id n = ref.num_points();
  std::vector<std::set<PointIndex>> near(static_cast<std::size_t>(n));
  for (Id t = 0; t < ref.num_cells(); ++t)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) near[ref.connectivity[3 * t + a]].insert(ref.connectivity[3 * t + b]);
  std::vector<std::uint8_t> taken(static_cast<std::size_t>(n), 0);
  // Points are free when nothing within two edges of them is taken yet;
  // their stars are then taken.
  auto claim = [&](std::vector<PointIndex> points) {
    for (PointIndex p : points)
      for (PointIndex q : near[p])
        for (PointIndex r : near[q])
          if (taken[r]) return false;
    for (PointIndex p : points)
      for (PointIndex q : near[p]) taken[q] = 1;
    return true;
  };
  std::mt19937 rng(5);
  std::vector<PointIndex> rename(static_cast<std::size_t>(n));
  for (Id p = 0; p < n; ++p) rename[p] = static_cast<PointIndex>(p);
  int pinches = 0, edges = 0;
  for (int tries = 0; tries < 4000 && (pinches < 20 || edges < 20); ++tries) {
    if (pinches < 20) {
      const PointIndex p = rng() % n, q = rng() % n;
      if (p != q && claim({p}) && claim({q})) rename[q] = p, ++pinches;
    }
    if (edges < 20) {
      // Triangle s's edge (a, b) and triangle u's edge (c, d): c becomes b
      // and d becomes a, so that u crosses the edge the other way.
      const Id s = rng() % ref.num_cells(), u = rng() % ref.num_cells();
      const PointIndex a = ref.connectivity[3 * s], b = ref.connectivity[3 * s + 1];
      const PointIndex c = ref.connectivity[3 * u], d = ref.connectivity[3 * u + 1];
      if (std::set<PointIndex>{a, b, c, d}.size() < 4) continue;
      if (!claim({a, b}) || !claim({c, d})) continue;  // marks of a failed try stay: fewer candidates only
      rename[c] = b, rename[d] = a, ++edges;
    }
  }
  ASSERT_EQ(pinches, 20);
  ASSERT_EQ(edges, 20);
  SurfaceMesh m = ref;
  for (PointIndex& id : m.connectivity) id = rename[id];
  const auto pinched = analyze::check_topology(m);
  EXPECT_EQ(pinched.nonmanifold_edges, 20);
  EXPECT_GE(pinched.nonmanifold_vertices, 20);
  // Also with the triangles shuffled (both meshes alike): a contour's come
  // in the order of their points, which the grouping of corners by point
  // uses; any other order must give the same answer.
  std::vector<std::size_t> order(static_cast<std::size_t>(ref.num_cells()));
  for (std::size_t t = 0; t < order.size(); ++t) order[t] = t;
  std::shuffle(order.begin(), order.end(), rng);
  auto shuffled = [&](const SurfaceMesh& x) {
    SurfaceMesh y = x;
    for (std::size_t t = 0; t < order.size(); ++t)
      for (int k = 0; k < 3; ++k) y.connectivity[3 * t + k] = x.connectivity[3 * order[t] + k];
    return y;
  };
  for (bool shuffle : {false, true})
    for (int threads : {1, 2, 3}) {
      parallel::set_thread_count(threads);
      SurfaceMesh s = shuffle ? shuffled(m) : m;
      const auto r = generate::split_nonmanifold(s);
      EXPECT_EQ(r.points_added, 20 + 2 * 20);
      EXPECT_EQ(r.edges_left, 0);
      EXPECT_TRUE(renamed(shuffle ? shuffled(ref) : ref, s)) << shuffle << " " << threads;
      const auto t = analyze::check_topology(s);
      EXPECT_TRUE(t.closed_manifold);
      EXPECT_EQ(t.euler_characteristic, topo.euler_characteristic);
      EXPECT_EQ(t.components, topo.components);
    }
  parallel::set_thread_count(0);
}

// White noise inside a low border: a closed fine surface whose coarsening
// pinches everywhere. After the rule no point has two fans and every edge
// crossed as often each way is manifold; the same at any thread count and
// on both coarsening paths.
TEST(SplitNonmanifold, CoarsenedNoiseIsAClosedManifold) {
  ImageGrid g;
  const Id n = 40;
  g.allocate({n, n, n}, ScalarType::Float32);
  std::mt19937 rng(2);
  auto* v = reinterpret_cast<float*>(g.data());
  for (Id p = 0; p < n * n * n; ++p) {
    const Id i = p % n, j = (p / n) % n, k = p / (n * n);
    const bool border = i == 0 || j == 0 || k == 0 || i == n - 1 || j == n - 1 || k == n - 1;
    v[p] = border ? 0.f : std::uniform_real_distribution<float>(0, 1)(rng);
  }
  generate::ContourOptions o;
  o.isovalues = {0.5};
  o.normals = generate::ContourNormals::None;
  const SurfaceMesh fine = generate::contour(g, o);
  o.coarsen = true;
  std::vector<SurfaceMesh> got;
  for (int threads : {1, 2})
    for (auto weld : {generate::ContourWeld::KeyReduce, generate::ContourWeld::KeyReduceSort}) {
      parallel::set_thread_count(threads);
      o.weld = weld;
      got.push_back(generate::contour(g, o));
    }
  parallel::set_thread_count(0);
  for (const SurfaceMesh& c : got) {
    EXPECT_EQ(c.points, got[0].points);
    EXPECT_EQ(c.connectivity, got[0].connectivity);
  }
  ASSERT_TRUE(analyze::check_topology(fine).closed_manifold);
  const SurfaceMesh& c = got[0];
  const auto t = analyze::check_topology(c);
  EXPECT_EQ(t.nonmanifold_vertices, 0);
  // Points whose every triangle collapsed or folded (white noise makes
  // many) are gone (mesh/unused_points.hpp).
  EXPECT_EQ(t.unused_points, 0);
  // Edges crossed as often each way are manifold; the others (where
  // remove_folds kept one of a set of equal triangles facing one way: white
  // noise makes a few) keep their unpaired triangles: three or more
  // triangles there count as non-manifold, one as boundary.
  std::map<std::pair<PointIndex, PointIndex>, std::pair<int, int>> ways;  // (smaller, larger): (up, down)
  for (Id tri = 0; tri < c.num_cells(); ++tri)
    for (int k = 0; k < 3; ++k) {
      const PointIndex a = c.connectivity[3 * tri + k], b = c.connectivity[3 * tri + (k + 1) % 3];
      auto& w = ways[{std::min(a, b), std::max(a, b)}];
      ++(a < b ? w.first : w.second);
    }
  Id unbalanced = 0, unbalanced_many = 0;
  for (const auto& [edge, w] : ways)
    if (w.first != w.second) ++unbalanced, unbalanced_many += w.first + w.second >= 3;
  // The others are the edges no rotation separated, which the rule counts
  // again when run on its own output (and then has nothing to split).
  SurfaceMesh again = c;
  const auto r = generate::split_nonmanifold(again);
  EXPECT_EQ(r.points_added, 0);
  EXPECT_EQ(t.nonmanifold_edges, unbalanced_many + r.edges_left);
  EXPECT_EQ(t.boundary_edges + unbalanced_many, unbalanced);
  // Fewer edges left than non-manifold ones (none with the table's shortest
  // splits on this volume, where the first-found splits left a few).
  if (t.nonmanifold_edges > 0) EXPECT_LT(r.edges_left, t.nonmanifold_edges);
  else EXPECT_EQ(r.edges_left, 0);
  // The copies: as many points at an earlier point's position as the rule
  // added, which is what a coarsening of white noise needs.
  EXPECT_GT(t.duplicate_points, 0);
}

}  // namespace
