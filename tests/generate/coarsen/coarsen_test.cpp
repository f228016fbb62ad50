#include "keymesh/generate/coarsen/coarsen.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>

#include "keymesh/analyze/quality.hpp"
#include "keymesh/analyze/topology.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/unstructured/contour_tets.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
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
  EXPECT_EQ(c.connectivity, (Array<PointIndex>{0, 1, 2}));
  EXPECT_FLOAT_EQ(c.points[3], 2.f);          // mean of x = 1 and x = 3
  EXPECT_FLOAT_EQ(c.point_fields[0].values[1], 4.f);  // mean of 2 and 6
}


// remove_folds against a reference written from its rule alone: triangles
// over the same three points form a set; a set of one stays; otherwise the
// orientations are summed (+1 / -1) and, if the sum is not zero, the first
// triangle of the winning orientation stays and the rest go; a zero sum
// drops the whole set. Random triangles over few points make many sets.
TEST(Coarsen, RemoveFoldsFollowsItsRule) {
  std::mt19937 rng(5);
  for (int round = 0; round < 20; ++round) {
    SurfaceMesh m;
    const std::uint32_t points = 4 + rng() % 12;
    m.points.assign(3 * points, 0.f);
    const int triangles = 1 + static_cast<int>(rng() % 400);
    for (int t = 0; t < triangles; ++t) {
      std::uint32_t a = rng() % points, b = rng() % points, c = rng() % points;
      while (b == a) b = rng() % points;
      while (c == a || c == b) c = rng() % points;
      m.connectivity.insert(m.connectivity.end(), {a, b, c});
    }
    // Reference.
    std::map<std::array<std::uint32_t, 3>, std::vector<int>> sets;
    auto sign = [&](int t) {
      const PointIndex* v = &m.connectivity[3 * t];
      // Even permutations of the sorted triple keep the orientation.
      std::array<std::uint32_t, 3> s{v[0], v[1], v[2]};
      int swaps = 0;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j + 1 < 3 - i; ++j)
          if (s[j] > s[j + 1]) std::swap(s[j], s[j + 1]), ++swaps;
      return std::make_pair(s, swaps % 2 == 0 ? 1 : -1);
    };
    for (int t = 0; t < triangles; ++t) sets[sign(t).first].push_back(t);
    std::vector<bool> keep(triangles, true);
    for (const auto& [key, members] : sets) {
      if (members.size() < 2) continue;
      int net = 0;
      for (int t : members) net += sign(t).second;
      bool kept = false;
      for (int t : members) {
        const bool winner = net != 0 && !kept && (sign(t).second > 0) == (net > 0);
        keep[t] = winner;
        kept = kept || winner;
      }
    }
    Array<PointIndex> expected;
    for (int t = 0; t < triangles; ++t)
      if (keep[t]) expected.insert(expected.end(), m.connectivity.begin() + 3 * t, m.connectivity.begin() + 3 * t + 3);
    const Id removed = generate::remove_folds(m);
    EXPECT_EQ(m.connectivity, expected) << "round " << round;
    EXPECT_EQ(removed, triangles - static_cast<Id>(expected.size() / 3));
  }
}

// remove_complete_folds, as the streamed coarsening calls it: the triangles
// come in two batches, every triangle on points below T in the first; the
// first call decides only the sets below T, the second (after the rest is
// appended, everything complete) the others. The result is remove_folds'
// over the whole list, and the first call's return is the first triangle it
// left undecided.
TEST(Coarsen, RemoveCompleteFoldsInBatchesEqualsRemoveFolds) {
  std::mt19937 rng(11);
  for (int round = 0; round < 20; ++round) {
    const std::uint32_t points = 6 + rng() % 10, below = 3 + rng() % (points - 4);
    auto triangle = [&](bool low) {
      std::array<std::uint32_t, 3> v{};
      do {
        for (auto& x : v) x = rng() % points;
      } while (v[0] == v[1] || v[1] == v[2] || v[0] == v[2] ||
               low != (std::max({v[0], v[1], v[2]}) < below));
      return v;
    };
    Array<PointIndex> first, second;
    for (int t = 0, n = 1 + static_cast<int>(rng() % 300); t < n; ++t) {
      const auto v = triangle(rng() % 2 == 0);  // below T or not, mixed
      first.insert(first.end(), v.begin(), v.end());
    }
    for (int t = 0, n = static_cast<int>(rng() % 300); t < n; ++t) {
      const auto v = triangle(false);
      second.insert(second.end(), v.begin(), v.end());
    }
    SurfaceMesh whole;
    whole.points.assign(3 * points, 0.f);
    whole.connectivity = first;
    whole.connectivity.insert(whole.connectivity.end(), second.begin(), second.end());
    generate::remove_folds(whole);
    Array<PointIndex> got = first;
    const Id left = generate::remove_complete_folds(got, 0, below);
    for (Id t = 0; t < left; ++t)
      EXPECT_LT(std::max({got[3 * t], got[3 * t + 1], got[3 * t + 2]}), below) << "round " << round;
    if (left < static_cast<Id>(got.size() / 3)) {
      EXPECT_GE(std::max({got[3 * left], got[3 * left + 1], got[3 * left + 2]}), below) << "round " << round;
    }
    got.insert(got.end(), second.begin(), second.end());
    const Id end = generate::remove_complete_folds(got, left, points);  // every set complete now
    EXPECT_EQ(end, static_cast<Id>(got.size() / 3)) << "round " << round;
    EXPECT_EQ(got, whole.connectivity) << "round " << round;
  }
}

// Coarsening in the contour's pass (the structured plan) equals coarsen()
// over the fine mesh (the sort plan's path) with NaN samples, which put
// their crossings midway (nearest the far end).
TEST(Coarsen, InThePassEqualsAfterTheContourWithNaNs) {
  ImageGrid g;
  g.allocate({33, 20, 17}, ScalarType::Float32);
  std::mt19937 rng(8);
  auto* v = reinterpret_cast<float*>(g.data());
  for (Id p = 0; p < g.num_points(); ++p)
    v[p] = rng() % 13 == 0 ? std::numeric_limits<float>::quiet_NaN() : std::uniform_real_distribution<float>(0, 1)(rng);
  for (int threads : {1, 2}) {
    parallel::set_thread_count(threads);
    generate::ContourOptions o;
    o.isovalues = {0.5, 0.2};
    o.coarsen = true;
    o.normals = generate::ContourNormals::Gradient;
    const SurfaceMesh rows = generate::contour(g, o);
    o.weld = generate::ContourWeld::KeyReduceSort;
    const SurfaceMesh sort = generate::contour(g, o);
    EXPECT_EQ(rows.points, sort.points);
    EXPECT_EQ(rows.connectivity, sort.connectivity);
    ASSERT_EQ(rows.point_fields.size(), sort.point_fields.size());
    for (std::size_t f = 0; f < rows.point_fields.size(); ++f)
      EXPECT_EQ(std::memcmp(rows.point_fields[f].values.data(), sort.point_fields[f].values.data(),
                            rows.point_fields[f].values.size() * sizeof(float)), 0);
  }
  parallel::set_thread_count(0);
}

// 8-bit samples take the pass's table of far ends (one answer per pair of
// end samples) instead of a division per edge; coarsen() after the sort
// plan's contour decides each crossing from its own t. Both agree on signed
// and unsigned bytes, with isovalues that put crossings exactly midway
// (t = 0.5: nearer the far end) and fractional ones.
TEST(Coarsen, InThePassEqualsAfterTheContourOnBytes) {
  for (const ScalarType type : {ScalarType::UInt8, ScalarType::Int8}) {
    ImageGrid g;
    g.allocate({31, 23, 19}, type);
    std::mt19937 rng(type == ScalarType::UInt8 ? 5 : 6);
    const Id n = g.num_points();
    for (Id p = 0; p < n; ++p) {
      const Id i = p % 31, j = p / 31 % 23, k = p / (31 * 23);
      const double smooth = 60 * std::sin(0.3 * i) * std::cos(0.25 * j) + 40 * std::sin(0.35 * k);
      const int v = static_cast<int>(std::lround(smooth)) + static_cast<int>(rng() % 9) - 4;  // -104 .. 104
      if (type == ScalarType::UInt8) static_cast<std::uint8_t*>(g.data())[p] = static_cast<std::uint8_t>(v + 128);
      else static_cast<std::int8_t*>(g.data())[p] = static_cast<std::int8_t>(v);
    }
    const double offset = type == ScalarType::UInt8 ? 128 : 0;
    generate::ContourOptions o;
    o.isovalues = {offset + 1, offset - 20.5, offset + 37.25};
    o.coarsen = true;
    for (int threads : {1, 2}) {
      parallel::set_thread_count(threads);
      o.weld = generate::ContourWeld::KeyReduce;
      const SurfaceMesh rows = generate::contour(g, o);
      o.weld = generate::ContourWeld::KeyReduceSort;
      const SurfaceMesh sort = generate::contour(g, o);
      ASSERT_GT(rows.num_cells(), 0);
      EXPECT_EQ(rows.points, sort.points) << static_cast<int>(type) << " threads " << threads;
      EXPECT_EQ(rows.connectivity, sort.connectivity) << static_cast<int>(type) << " threads " << threads;
    }
  }
  parallel::set_thread_count(0);
}

// The coarse points' pass (every coarse point the mean of its crossings,
// summed in edge-key order) against coarsen() over the fine mesh, for each
// set of fields it writes: positions alone, with the scalar, with gradient
// normals, with curvature. Rows of 150 samples span three 64-point words, so
// a crossing merged into the first point of a word from the x edge before
// it (in the previous word) is there; several isovalues; float and double
// samples; an origin and spacings that are not whole numbers (one
// negative); 1 and 2 threads.
TEST(Coarsen, InThePassEqualsAfterTheContourForEveryField) {
  struct Fields {
    bool scalars, curvature;
    generate::ContourNormals normals;
  };
  const Fields fields[] = {{false, false, generate::ContourNormals::None},
                           {true, false, generate::ContourNormals::None},
                           {true, false, generate::ContourNormals::Gradient},
                           {false, true, generate::ContourNormals::None},
                           {true, true, generate::ContourNormals::Gradient}};
  for (const ScalarType type : {ScalarType::Float32, ScalarType::Float64}) {
    ImageGrid g;
    g.allocate({150, 21, 13}, type);
    g.origin = {-3.25, 0.1, 7.0};
    g.spacing = {0.3, -1.7, 0.45};
    std::mt19937 rng(type == ScalarType::Float32 ? 11 : 12);
    for (Id p = 0; p < g.num_points(); ++p) {
      const Id i = p % 150, j = p / 150 % 21, k = p / (150 * 21);
      const double v = std::sin(0.21 * i) * std::cos(0.4 * j) + 0.5 * std::sin(0.6 * k) +
                       0.2 * std::uniform_real_distribution<double>(-1, 1)(rng);
      if (type == ScalarType::Float32) reinterpret_cast<float*>(g.data())[p] = static_cast<float>(v);
      else reinterpret_cast<double*>(g.data())[p] = v;
    }
    for (const Fields& f : fields) {
      generate::ContourOptions o;
      o.isovalues = {0.1, -0.45, 0.6};
      o.coarsen = true;
      o.scalars = f.scalars;
      o.curvature = f.curvature;
      o.normals = f.normals;
      o.weld = generate::ContourWeld::KeyReduceSort;
      const SurfaceMesh sort = generate::contour(g, o);
      ASSERT_GT(sort.num_cells(), 1000);
      o.weld = generate::ContourWeld::KeyReduce;
      for (int threads : {1, 2}) {
        parallel::set_thread_count(threads);
        const SurfaceMesh rows = generate::contour(g, o);
        const std::string what = std::to_string(static_cast<int>(type)) + " scalars " + std::to_string(f.scalars) +
                                 " curvature " + std::to_string(f.curvature) + " threads " + std::to_string(threads);
        EXPECT_EQ(std::memcmp(rows.points.data(), sort.points.data(), sort.points.size() * sizeof(float)), 0) << what;
        EXPECT_EQ(rows.points.size(), sort.points.size()) << what;
        EXPECT_EQ(rows.connectivity, sort.connectivity) << what;
        ASSERT_EQ(rows.point_fields.size(), sort.point_fields.size()) << what;
        for (std::size_t n = 0; n < rows.point_fields.size(); ++n) {
          ASSERT_EQ(rows.point_fields[n].values.size(), sort.point_fields[n].values.size()) << what;
          EXPECT_EQ(std::memcmp(rows.point_fields[n].values.data(), sort.point_fields[n].values.data(),
                                rows.point_fields[n].values.size() * sizeof(float)), 0)
              << what << " " << rows.point_fields[n].name;
        }
      }
    }
  }
  parallel::set_thread_count(0);
}

// The pass decides folds voxel by voxel and face by face (coarse_folds.hpp,
// the tabulated voxels of coarse_cases.hpp); coarsen() compares the whole
// mesh's triangles (remove_folds). On coarse random volumes, where many
// triangles fold within voxels and across faces, and on a smooth one, both
// give the same bytes at 1 and 2 threads, and the folds were there to find.
TEST(Coarsen, FoldsDecidedInThePassEqualTheWholeMeshRule) {
  struct Case {
    std::array<Id, 3> dims;
    int levels;  // sample values 0..levels-1 (random), 0 for a smooth field
    std::vector<double> isovalues;
  };
  const Case cases[] = {{{23, 17, 13}, 4, {1.5}}, {{16, 31, 9}, 3, {0.5, 1.5}}, {{40, 40, 40}, 0, {0.37, 0.5}}};
  for (const Case& c : cases) {
    ImageGrid g;
    g.allocate(c.dims, ScalarType::Float32);
    auto* v = reinterpret_cast<float*>(g.data());
    std::mt19937 rng(static_cast<unsigned>(c.dims[0]));
    for (Id p = 0; p < g.num_points(); ++p) {
      const Id i = p % c.dims[0], j = p / c.dims[0] % c.dims[1], k = p / (c.dims[0] * c.dims[1]);
      v[p] = c.levels ? static_cast<float>(rng() % static_cast<unsigned>(c.levels))
                      : static_cast<float>(0.5 + 0.3 * std::sin(0.4 * i) * std::cos(0.3 * j) + 0.2 * std::sin(0.5 * k));
    }
    generate::ContourOptions o;
    o.isovalues = c.isovalues;
    // The fine mesh and its nearest-point keys, coarsened after: the folds it finds.
    std::vector<std::uint64_t> nearest;
    const SurfaceMesh fine = generate::contour(g, o, nullptr, nullptr, &nearest);
    generate::CoarsenStats cs;
    const SurfaceMesh after = generate::coarsen(
        fine, nearest, static_cast<std::uint64_t>(g.num_points()) * c.isovalues.size(), &cs);
    if (c.levels) {
      EXPECT_GT(cs.folded, 0) << c.dims[0];
    }
    o.coarsen = true;
    for (int threads : {1, 2}) {
      parallel::set_thread_count(threads);
      const SurfaceMesh in_pass = generate::contour(g, o);
      EXPECT_EQ(in_pass.connectivity, after.connectivity) << c.dims[0] << " threads " << threads;
      EXPECT_EQ(in_pass.points, after.points) << c.dims[0] << " threads " << threads;
      EXPECT_EQ(duplicate_triangles(in_pass), 0);
    }
  }
  parallel::set_thread_count(0);
}

// The pass finds the points to split from the voxels around each point
// (coarse_fans.hpp: a point's fan read from its eight voxels' table
// entries, suspects checked against the triangles again); coarsen() groups
// every corner by point (split_nonmanifold). On random volumes of two and
// three levels, where sheets pinch and share edges at many points, both give
// the same bytes at 1 and 2 threads, points were split (their copies sit on
// the original: coincident positions), and no point is left without a
// triangle (the pass numbers none).
TEST(Coarsen, SuspectsFromTheVoxelsSplitAsTheWholeMeshRule) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    const std::array<Id, 3> dims{17 + seed, 13 + 2 * seed, 11 + seed % 3};
    ImageGrid g;
    g.allocate(dims, ScalarType::Float32);
    auto* v = reinterpret_cast<float*>(g.data());
    std::mt19937 rng(seed);
    const unsigned levels = seed % 2 ? 2 : 3;
    for (Id p = 0; p < g.num_points(); ++p)
      v[p] = static_cast<float>(rng() % levels) + std::uniform_real_distribution<float>(-0.3f, 0.3f)(rng);
    generate::ContourOptions o;
    o.isovalues = {0.5, 1.5};
    std::vector<std::uint64_t> nearest;
    const SurfaceMesh fine = generate::contour(g, o, nullptr, nullptr, &nearest);
    const SurfaceMesh after =
        generate::coarsen(fine, nearest, static_cast<std::uint64_t>(g.num_points()) * o.isovalues.size());
    std::set<std::array<float, 3>> positions;
    for (Id p = 0; p < after.num_points(); ++p)
      positions.insert({after.points[3 * p], after.points[3 * p + 1], after.points[3 * p + 2]});
    EXPECT_LT(static_cast<Id>(positions.size()), after.num_points()) << "seed " << seed << ": nothing was split";
    o.coarsen = true;
    for (int threads : {1, 2}) {
      parallel::set_thread_count(threads);
      const SurfaceMesh in_pass = generate::contour(g, o);
      EXPECT_EQ(in_pass.connectivity, after.connectivity) << "seed " << seed << " threads " << threads;
      EXPECT_EQ(in_pass.points, after.points) << "seed " << seed << " threads " << threads;
      std::vector<std::uint8_t> used(static_cast<std::size_t>(in_pass.num_points()), 0);
      for (PointIndex c : in_pass.connectivity) used[c] = 1;
      EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0) << "seed " << seed;
    }
  }
  parallel::set_thread_count(0);
}

}  // namespace
