// The walk of the coarse points' pass (src/generate/coarsen/contour_coarse_rows.hpp,
// CoarseRow) against a brute force over the grid's edges: every cut edge's
// crossing comes exactly once, to the coarse point at the edge's end
// nearest to it, each point's crossings in increasing edge key (the order
// of a KEY-REDUCE over the fine points, which the pass's sums must follow:
// a float sum's rounding depends on it), and the points come with their
// ranks among the coarse points (ids in key order). Wide rows (several
// 64-point words) and 1 and 2 threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <mutex>
#include <random>
#include <vector>

#include "generate/grid_shape.hpp"
#include "generate/coarsen/contour_coarse_rows.hpp"
#include "keymesh/parallel/threads.hpp"

using namespace keymesh;
using namespace keymesh::generate;

namespace {

TEST(CoarseRows, EveryCrossingOnceToItsNearestEndInKeyOrder) {
  const GridShape s = grid_shape(150, 9, 7);
  std::vector<float> v(static_cast<std::size_t>(s.n));
  std::mt19937 rng(3);
  for (Id p = 0; p < s.n; ++p)
    v[p] = std::sin(0.2f * static_cast<float>(p % s.nx)) + std::uniform_real_distribution<float>(-0.6f, 0.6f)(rng);
  const double iso = 0.15;
  auto far_end = [&](Id p0, int axis) {
    const double t = (iso - v[p0]) / (v[p0 + s.stride[axis]] - v[p0]);
    return !std::isfinite(t) || t >= 0.5;
  };
  // The reference: grid point -> the edge keys 3 p0 + axis merged into it, increasing.
  std::map<Id, std::vector<Id>> expected;
  for (Id p = 0; p < s.n; ++p) {
    const Id ijk[3] = {p % s.nx, p / s.nx % s.ny, p / s.nxy};
    const Id dims[3] = {s.nx, s.ny, s.nz};
    for (int a = 0; a < 3; ++a) {
      if (ijk[a] + 1 >= dims[a] || (v[p] >= iso) == (v[p + s.stride[a]] >= iso)) continue;
      expected[far_end(p, a) ? p + s.stride[a] : p].push_back(3 * p + a);
    }
  }
  for (auto& [point, keys] : expected) std::sort(keys.begin(), keys.end());
  ASSERT_GT(expected.size(), 500u);

  for (int threads : {1, 2}) {
    parallel::set_thread_count(threads);
    InsideBits bits;
    classify(v.data(), s, InsideTest<float>(iso), bits);
    RowCounts rc;
    count_rows(bits, s, 0, s.nz - 1, 0, 0, rc);
    CoarseBits cb;
    mark_coarse_points(bits, s, rc, v.data(), [&](float v0, float v1) {
      const double t = (iso - v0) / (v1 - v0);
      return !std::isfinite(t) || t >= 0.5;
    }, cb);
    // A candidate taken out (as check_coarse_fans takes out those left
    // without a triangle): neither it nor its crossings are met.
    const Id out = std::next(expected.begin(), static_cast<std::ptrdiff_t>(expected.size() / 2))->first;
    const Id out_row = out / s.nx, out_i = out % s.nx;
    cb.points.data()[out_row * cb.words_per_row + out_i / 64] &= ~(std::uint64_t{1} << (out_i % 64));
    number_coarse_points(s, 0, cb);
    std::map<Id, std::vector<Id>> kept = expected;
    kept.erase(out);
    ASSERT_EQ(cb.count, static_cast<Id>(kept.size()));
    std::map<Id, std::vector<Id>> met;  // point -> edge keys, in the order the walk gave them
    std::map<Id, std::uint32_t> ids;
    std::mutex m;
    for_each_coarse_row(bits, s, cb, [&](const CoarseRow& row) {
      const Id base = row.j * s.nx + row.k * s.nxy;
      std::lock_guard<std::mutex> lock(m);
      row.for_each_crossing([&](Id i, const CoarseCrossing& x, auto axis) {
        EXPECT_EQ(x.axis, decltype(axis)::value);
        met[base + i].push_back(3 * (x.i + x.j * s.nx + x.k * s.nxy) + x.axis);
      });
      row.for_each_point([&](Id i, std::uint32_t id) { EXPECT_TRUE(ids.emplace(base + i, id).second); });
    });
    EXPECT_EQ(met, kept) << "threads " << threads;
    ASSERT_EQ(ids.size(), kept.size());
    std::uint32_t rank = 0;
    for (const auto& [point, id] : ids) EXPECT_EQ(id, rank++) << "point " << point;
  }
  parallel::set_thread_count(0);
}

}  // namespace
