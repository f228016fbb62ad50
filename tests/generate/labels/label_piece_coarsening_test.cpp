// Coarsening a multilod chunk piece (merge_piece_points,
// src/generate/labels/label_coarsen.cpp): points of one coarse key averaged,
// collapsed triangles dropped, opposite ones on the same points cancelled,
// unused points dropped; and the serial grouping small pieces take gives
// exactly what the parallel KEY-REDUCE plans give.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "generate/labels/label_chunks.hpp"

using namespace keymesh;
using generate::MultilodPiece;
using generate::detail::merge_piece_points;

namespace {

MultilodPiece merged(const MultilodPiece& finer, const std::vector<std::uint64_t>& coarse, Id serial_below) {
  MultilodPiece out;
  merge_piece_points(finer, coarse, out, serial_below);
  return out;
}

}  // namespace

TEST(PieceCoarsening, MergesCollapsesAndCancels) {
  MultilodPiece finer;
  finer.point_keys = {1, 2, 3, 4, 5, 6};
  finer.points = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1.5f, 0.25f, 0, 0, 0, 1, 7, 7, 7};
  // (0 1 2) and (0 2 1): opposite on the same points, both go; (0 1 3):
  // 1 and 3 merge, it collapses; (0 1 4) twice and (0 4 1) once: one stays.
  // Point 5 is on no triangle.
  finer.triangles = {0, 1, 2, 0, 2, 1, 0, 1, 3, 0, 1, 4, 0, 4, 1, 0, 1, 4};
  const std::vector<std::uint64_t> coarse = {10, 20, 30, 20, 40, 50};
  for (Id serial_below : {generate::detail::kCoarsenSerialBelow, Id{0}}) {
    const MultilodPiece out = merged(finer, coarse, serial_below);
    EXPECT_EQ(out.point_keys, (std::vector<std::uint64_t>{10, 20, 40}));  // 30 and 50 used by no kept triangle
    EXPECT_EQ(out.triangles, (std::vector<std::uint32_t>{0, 1, 2}));
    EXPECT_EQ(out.points, (std::vector<float>{0, 0, 0, 1.25f, 0.125f, 0, 0, 0, 1}));
  }
}

TEST(PieceCoarsening, SerialGroupingEqualsTheParallelPlans) {
  std::mt19937 rng(37);
  for (int round = 0; round < 4; ++round) {
    const std::uint32_t n = 3000;
    MultilodPiece finer;
    std::uniform_real_distribution<float> at(-1.0f, 33.0f);
    for (std::uint32_t i = 0; i < n; ++i) {
      finer.point_keys.push_back(i);
      for (int a = 0; a < 3; ++a) finer.points.push_back(at(rng));
    }
    std::uniform_int_distribution<std::uint32_t> point(0, n - 1);
    for (int t = 0; t < 9000; ++t) {
      const std::uint32_t a = point(rng), b = point(rng), c = point(rng);
      finer.triangles.insert(finer.triangles.end(), {a, b, c});
      if (t % 5 == 0) finer.triangles.insert(finer.triangles.end(), {a, c, b});  // to cancel
      if (t % 7 == 0) finer.triangles.insert(finer.triangles.end(), {b, c, a});  // the same, rotated
    }
    std::uniform_int_distribution<std::uint64_t> key(0, 200 + 600 * static_cast<std::uint64_t>(round));
    std::vector<std::uint64_t> coarse(n);
    for (auto& k : coarse) k = key(rng) << (17 * round);  // up to 62 significant bits
    const MultilodPiece serial = merged(finer, coarse, generate::detail::kCoarsenSerialBelow);
    const MultilodPiece parallel = merged(finer, coarse, 0);
    EXPECT_FALSE(serial.triangles.empty());
    EXPECT_LT(serial.triangles.size(), finer.triangles.size());
    EXPECT_EQ(serial.point_keys, parallel.point_keys);
    EXPECT_EQ(serial.points, parallel.points);
    EXPECT_EQ(serial.triangles, parallel.triangles);
  }
}
