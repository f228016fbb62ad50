#include "keymesh/parallel/radix_sort.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "thread_count_test.hpp"

namespace kp = keymesh::parallel;

namespace {

// Reference: std::stable_sort of (key, original position).
template <class K>
void expect_sorted_like_stable_sort(std::vector<K> keys, int bits) {
  std::vector<std::uint32_t> values(keys.size());
  std::iota(values.begin(), values.end(), 0u);
  std::vector<std::pair<K, std::uint32_t>> ref;
  for (std::size_t i = 0; i < keys.size(); ++i) ref.emplace_back(keys[i], std::uint32_t(i));
  std::stable_sort(ref.begin(), ref.end(), [](auto& a, auto& b) { return a.first < b.first; });
  kp::sort_pairs(keys, values, bits);
  ASSERT_EQ(keys.size(), ref.size());
  for (std::size_t i = 0; i < ref.size(); ++i) {
    ASSERT_EQ(keys[i], ref[i].first) << "at " << i;
    ASSERT_EQ(values[i], ref[i].second) << "at " << i;
  }
}

class RadixSortThreads : public keymesh::tests::ThreadCountTest {};

}  // namespace

TEST_P(RadixSortThreads, Empty) { expect_sorted_like_stable_sort<std::uint64_t>({}, 64); }

TEST_P(RadixSortThreads, OneElement) { expect_sorted_like_stable_sort<std::uint32_t>({42u}, 32); }

TEST_P(RadixSortThreads, AllKeysEqualKeepInputOrder) {
  expect_sorted_like_stable_sort<std::uint64_t>(std::vector<std::uint64_t>(300000, 7u), 64);
}

TEST_P(RadixSortThreads, KeysAtTopOfRange64) {
  std::mt19937_64 rng(1);
  std::vector<std::uint64_t> keys(200000);
  for (auto& k : keys) k = ~std::uint64_t{0} - (rng() % 1000);
  expect_sorted_like_stable_sort(keys, 64);
}

TEST_P(RadixSortThreads, KeysAtTopOfRange32) {
  std::mt19937 rng(2);
  std::vector<std::uint32_t> keys(200000);
  for (auto& k : keys) k = 0xFFFFFFFFu - (rng() % 5000);
  expect_sorted_like_stable_sort(keys, 32);
}

TEST_P(RadixSortThreads, RandomWithSignificantBitsHint) {
  std::mt19937_64 rng(3);
  std::vector<std::uint64_t> keys(250000);
  for (auto& k : keys) k = rng() & ((std::uint64_t{1} << 21) - 1);
  expect_sorted_like_stable_sort(keys, 21);
}

TEST_P(RadixSortThreads, ManyDuplicates) {
  std::mt19937 rng(4);
  std::vector<std::uint32_t> keys(250000);
  for (auto& k : keys) k = rng() % 17;
  expect_sorted_like_stable_sort(keys, kp::bits_needed(16u));
}

// Below about passes x buckets / 8 pairs the sort compares instead of
// running passes: both sides of that size, 64- and 32-bit keys, with
// duplicates, give the stable order.
TEST_P(RadixSortThreads, FewAndManyPairsAlike) {
  std::mt19937_64 rng(9);
  for (std::size_t n : {2u, 3u, 17u, 100u, 767u, 768u, 769u, 1535u, 1536u, 1537u, 5000u}) {
    std::vector<std::uint64_t> keys(n);
    for (auto& k : keys) k = (rng() % 40) << (rng() % 2 ? 50 : 3);
    expect_sorted_like_stable_sort(keys, 64);
    std::vector<std::uint32_t> small(n);
    for (auto& k : small) k = static_cast<std::uint32_t>(rng() % 60) << 20;
    expect_sorted_like_stable_sort(small, 32);
  }
}

// Bits above significant_bits are not sorted on (the caller promises none):
// the comparison sort for few pairs and the passes for many order alike.
TEST_P(RadixSortThreads, OnlyTheSignificantBitsOrder) {
  std::mt19937_64 rng(10);
  for (std::size_t n : {50u, 20000u}) {
    std::vector<std::uint64_t> keys(n);
    for (auto& k : keys) k = rng();
    std::vector<std::uint32_t> values(n);
    std::iota(values.begin(), values.end(), 0u);
    std::vector<std::uint32_t> expected = values;
    std::stable_sort(expected.begin(), expected.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return (keys[a] & 0xFFFFF) < (keys[b] & 0xFFFFF); });
    kp::sort_pairs(keys, values, 20);
    EXPECT_EQ(values, expected) << n << " pairs";
  }
}

INSTANTIATE_TEST_SUITE_P(Threads, RadixSortThreads, ::testing::Values(1, 2, 3));

TEST(BitsNeeded, Values) {
  EXPECT_EQ(kp::bits_needed(0u), 0);
  EXPECT_EQ(kp::bits_needed(1u), 1);
  EXPECT_EQ(kp::bits_needed(255u), 8);
  EXPECT_EQ(kp::bits_needed(256u), 9);
  EXPECT_EQ(kp::bits_needed(~std::uint64_t{0}), 64);
}
