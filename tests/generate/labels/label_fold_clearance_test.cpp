// The fold guard's clearance (src/generate/labels/label_fold_clearance.cpp)
// proves only what the guard's own test finds, down to the last bit: a
// triangle it clears passes every orientation GuardStep computes on any try
// (the moving corner at 1, 1/2, 1/4 or 1/8 of its move), even where the
// bound is tight; and the guard with it moves every point exactly as without
// it, on jittered meshes with moves small and large.
#include "generate/labels/label_fold_clearance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "keymesh/generate/labels/label_kernels.hpp"

using namespace keymesh;
using generate::detail::FoldClearance;
using generate::detail::clearance_slack;
using generate::detail::triangle_clear;
using generate::label_kernels::orientation;

namespace {

// GuardStep's try at fraction f for corner k of triangle (a, b, c) (moves
// da, db, dc): at = x + f (candidate - x), the two others at either end; the
// least of the four orientations it computes.
double try_least(const double pos[3][3], const double cand[3][3], int k, double f, const double* n) {
  double at[3];
  for (int a = 0; a < 3; ++a) at[a] = pos[k][a] + f * (cand[k][a] - pos[k][a]);
  const double* qs[2] = {pos[(k + 1) % 3], cand[(k + 1) % 3]};
  const double* rs[2] = {pos[(k + 2) % 3], cand[(k + 2) % 3]};
  double least = INFINITY;
  for (const double* q : qs)
    for (const double* r : rs) least = std::fmin(least, orientation(at, q, r, n));
  return least;
}

double length(const double v[3]) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

}  // namespace

// Tight cases: one corner moves straight at its opposite side in the
// triangle's plane, where the bound is the least orientation itself (up to
// rounding), far from the origin, with `least` set within a few slack widths
// of it; and loose ones (every corner moving anywhere). A cleared triangle
// passes all twelve orientations of every try; both answers occur.
TEST(LabelFoldClearance, ClearedTrianglesPassEveryOrientationOfEveryTry) {
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int cleared = 0, refused = 0;
  for (int i = 0; i < 200000; ++i) {
    // Tight at the full move (towards the opposite side), tight at every
    // fraction of it (along the opposite side: D stays), or loose.
    const bool tight = i % 4 < 2, sliding = i % 4 == 1;
    const double far = i % 3 == 0 ? 1000.0 : 50.0;
    double pos[3][3], cand[3][3];
    for (int a = 0; a < 3; ++a) {
      const double o = far * unit(rng);
      pos[0][a] = o;
      pos[1][a] = o + (a == 0 ? 1.0 : 0.0) + 0.3 * unit(rng);
      pos[2][a] = o + (a == 1 ? 1.0 : 0.0) + 0.3 * unit(rng);
    }
    const double u[3] = {pos[1][0] - pos[0][0], pos[1][1] - pos[0][1], pos[1][2] - pos[0][2]};
    const double v[3] = {pos[2][0] - pos[0][0], pos[2][1] - pos[0][1], pos[2][2] - pos[0][2]};
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double twice_area = length(n);
    for (double& c : n) c /= twice_area;
    std::memcpy(cand, pos, sizeof pos);
    double reach[3] = {0, 0, 0};
    if (tight) {
      // Corner 0 towards side (1, 2): along (p2 - p1) x n, the in-plane
      // normal of that side pointing inwards; or along that side.
      const double s[3] = {pos[2][0] - pos[1][0], pos[2][1] - pos[1][1], pos[2][2] - pos[1][2]};
      const double in[3] = {s[1] * n[2] - s[2] * n[1], s[2] * n[0] - s[0] * n[2], s[0] * n[1] - s[1] * n[0]};
      const double* dir = sliding ? s : in;
      const double step = 0.5 * (unit(rng) + 1.0) / length(dir);
      for (int a = 0; a < 3; ++a) cand[0][a] = pos[0][a] + step * dir[a];
    } else {
      const double scale = std::pow(10.0, -3.0 + 3.0 * (unit(rng) + 1.0) / 2.0);
      for (auto& c : cand)
        for (double& x : c) x += scale * unit(rng);
    }
    for (int k = 0; k < 3; ++k) {
      const double d[3] = {cand[k][0] - pos[k][0], cand[k][1] - pos[k][1], cand[k][2] - pos[k][2]};
      reach[k] = length(d);
    }
    double size = 0;
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) size = std::fmax(size, std::fmax(std::fabs(pos[k][a]), std::fabs(cand[k][a])));
    // The first try's least (the tight one: the bound's own case), and the
    // least over every try.
    double truth = INFINITY, every = INFINITY;
    for (int k = 0; k < 3; ++k) {
      truth = std::fmin(truth, try_least(pos, cand, k, 1.0, n));
      for (double f : {1.0, 0.5, 0.25, 0.125}) every = std::fmin(every, try_least(pos, cand, k, f, n));
    }
    // least from 1e-17 to 1e-8 (times the coordinates' size) either side of
    // the truth, across rounding and the clearance's slack (tight), or
    // anywhere below twice the area (loose).
    const double off = std::pow(10.0, -17.0 + 4.5 * (unit(rng) + 1.0)) * (1.0 + size);
    const double least = tight ? (sliding ? every : truth) + (unit(rng) < 0 ? -off : off)
                               : twice_area * (unit(rng) + 1.0) / 2.0;
    const double* from[3] = {pos[0], pos[1], pos[2]};
    const double* to[3] = {cand[0], cand[1], cand[2]};
    if (triangle_clear(from, to, reach, n, least, clearance_slack(size))) {
      ++cleared;
      ASSERT_GE(every, least) << "case " << i;
    } else {
      ++refused;
    }
  }
  EXPECT_GT(cleared, 20000);
  EXPECT_GT(refused, 20000);
}

// A jittered sheet of 2 x 40 x 40 triangles; GuardStep with and without the
// clearance, over moves from a thousandth to most of a side, several steps
// each: the same positions bit for bit and the same shortened counts; a
// point is clear where all its triangles are.
TEST(LabelFoldClearance, GuardStepMovesEveryPointAsWithout) {
  constexpr int kSide = 41;
  const Id points = kSide * kSide, triangles = 2 * (kSide - 1) * (kSide - 1);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<float> start(static_cast<std::size_t>(3 * points));
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) {
      float* p = start.data() + 3 * (j * kSide + i);
      p[0] = static_cast<float>(-70.0 + i + 0.2 * unit(rng));
      p[1] = static_cast<float>(30.0 + j + 0.2 * unit(rng));
      p[2] = static_cast<float>(12.0 + 0.2 * unit(rng));
    }
  std::vector<std::uint32_t> corners;
  for (int j = 0; j + 1 < kSide; ++j)
    for (int i = 0; i + 1 < kSide; ++i) {
      const std::uint32_t a = j * kSide + i, b = a + 1, c = a + kSide + 1, d = a + kSide;
      for (std::uint32_t v : {a, b, c, a, c, d}) corners.push_back(v);
    }
  std::vector<std::uint8_t> junction(static_cast<std::size_t>(points));
  for (auto& j : junction) j = unit(rng) > 0.6;
  std::vector<double> normal(static_cast<std::size_t>(3 * triangles)), least(static_cast<std::size_t>(triangles));
  const generate::label_kernels::GuardFrame frame{start.data(), corners.data(), junction.data(), normal.data(),
                                                  least.data()};
  for (Id t = 0; t < triangles; ++t) frame(t);
  // Each point's corners, in corner order.
  std::vector<Id> offsets(static_cast<std::size_t>(points + 1), 0);
  for (std::uint32_t v : corners) ++offsets[v + 1];
  for (Id p = 0; p < points; ++p) offsets[p + 1] += offsets[p];
  std::vector<std::uint32_t> point_corners(corners.size());
  std::vector<Id> fill(offsets.begin(), offsets.end() - 1);
  for (std::uint32_t c = 0; c < corners.size(); ++c) point_corners[fill[corners[c]]++] = c;
  int cleared = 0, tested = 0, shortened = 0, points_clear = 0;
  for (double scale : {1e-3, 1e-2, 0.1, 0.3, 0.7}) {
    std::vector<double> x(start.begin(), start.end()), candidate(x.size()), plain(x.size()), fast(x.size());
    for (int step = 0; step < 4; ++step) {
      for (std::size_t i = 0; i < x.size(); ++i) candidate[i] = x[i] + scale * unit(rng);
      std::vector<std::uint32_t> count_plain(static_cast<std::size_t>(points)), count_fast(count_plain);
      generate::label_kernels::GuardStep guard{corners.data(), offsets.data(), point_corners.data(), normal.data(),
                                               least.data(), x.data(), candidate.data(), plain.data(),
                                               count_plain.data()};
      for (Id p = 0; p < points; ++p) guard(p);
      FoldClearance clearance;
      clearance.update({corners.data(), normal.data(), least.data(), x.data(), candidate.data(), points, triangles});
      guard.clear = clearance.clear(), guard.clear_point = clearance.clear_point();
      guard.out = fast.data(), guard.shortened = count_fast.data();
      for (Id p = 0; p < points; ++p) guard(p);
      ASSERT_EQ(0, std::memcmp(plain.data(), fast.data(), plain.size() * sizeof(double))) << scale << " " << step;
      ASSERT_EQ(count_plain, count_fast) << scale << " " << step;
      for (Id t = 0; t < triangles; ++t) (clearance.clear()[t] ? cleared : tested) += 1;
      for (Id p = 0; p < points; ++p) {
        bool all = true;
        for (Id j = offsets[p]; j < offsets[p + 1]; ++j) all = all && clearance.clear()[point_corners[j] / 3];
        ASSERT_EQ(all, clearance.clear_point()[p] == 1) << "point " << p;
        points_clear += all;
      }
      for (std::uint32_t c : count_plain) shortened += static_cast<int>(c);
      x.swap(plain);
    }
  }
  EXPECT_GT(cleared, 1000);
  EXPECT_GT(tested, 1000);
  EXPECT_GT(shortened, 100);
  EXPECT_GT(points_clear, 1000);
}
