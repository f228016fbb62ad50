// The cut-voxel walk of src/generate/contour/voxel_bits.hpp against a brute force
// over the grid: every voxel with corners on both sides comes once, in
// increasing i, with its cube case (corner c = x | y << 1 | z << 2 inside:
// bit c), whether its word's cases are made one at a time or 64 at once
// (cube_cases_of_word, the dense words' way), and the 64-at-once cases
// equal the one-at-a-time ones for random words.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "generate/grid_shape.hpp"
#include "generate/contour/voxel_bits.hpp"

using namespace keymesh;
using namespace keymesh::generate;

namespace {

TEST(VoxelBits, CasesOfAWordAtOnceEqualOneAtATime) {
  std::mt19937_64 rng(7);
  for (int round = 0; round < 2000; ++round) {
    // Four rows' words and the next words (a1 .. d1: corner i + 1, as the walk makes them).
    std::uint64_t row[4] = {rng(), rng(), rng(), rng()}, next[4] = {rng(), rng(), rng(), rng()};
    if (round % 3 == 0) row[2] = row[0], row[3] = ~row[1];  // correlated rows too
    auto shifted = [&](int r) { return (row[r] >> 1) | (next[r] << 63); };
    const CornerWords w{row[0], row[1], row[2], row[3], shifted(0), shifted(1), shifted(2), shifted(3)};
    std::uint8_t cases[64];
    cube_cases_of_word(w, cases);
    for (int b = 0; b < 64; ++b) ASSERT_EQ(unsigned{cases[b]}, cube_case_at(b, w)) << "round " << round << " bit " << b;
  }
}

TEST(VoxelBits, EveryCutVoxelOnceWithItsCaseSparseAndDense) {
  const GridShape s = grid_shape(200, 7, 6);
  std::vector<float> v(static_cast<std::size_t>(s.n));
  std::mt19937 rng(11);
  // Noise in the first half of each row (most voxels cut: dense words),
  // a smooth ramp in the second (few cut voxels: sparse words).
  for (Id p = 0; p < s.n; ++p) {
    const Id i = p % s.nx;
    v[p] = i < 100 ? std::uniform_real_distribution<float>(-1, 1)(rng) : 0.02f * static_cast<float>(i - 150) + 0.1f * static_cast<float>(p / s.nx % 3);
  }
  InsideBits bits;
  classify(v.data(), s, InsideTest<float>(0.0), bits);
  auto inside = [&](Id i, Id j, Id k) { return v[i + j * s.nx + k * s.nxy] >= 0.0f; };
  Id dense_words = 0;
  for (Id k = 0; k + 1 < s.nz; ++k)
    for (Id j = 0; j + 1 < s.ny; ++j) {
      std::vector<std::pair<Id, unsigned>> expected, met;
      for (Id i = 0; i + 1 < s.nx; ++i) {
        unsigned c = 0;
        for (unsigned corner = 0; corner < 8; ++corner)
          c |= unsigned{inside(i + (corner & 1u), j + ((corner >> 1) & 1u), k + (corner >> 2))} << corner;
        if (c != 0 && c != 255) expected.emplace_back(i, c);
      }
      for_each_cut_voxel(bits, s, j, k, [&](Id i, unsigned c) { met.emplace_back(i, c); });
      EXPECT_EQ(met, expected) << "row " << j << " layer " << k;
      for (Id q = 0; q < 4; ++q) {
        Id n = 0;
        for (const auto& [i, c] : expected) n += i / 64 == q;
        dense_words += n >= 8;
      }
    }
  EXPECT_GT(dense_words, 0);  // both ways were taken
}

}  // namespace
