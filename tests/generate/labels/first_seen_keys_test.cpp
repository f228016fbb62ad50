// Keys numbered in first-seen order by a hash table (first_seen_keys,
// src/generate/labels/first_seen_keys.cpp), against a std::map reference:
// with few distinct keys (long probe chains in a small table) and with keys
// that share their low or high bits.
#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include "generate/labels/first_seen_keys.hpp"

using namespace keymesh;
using generate::detail::first_seen_keys;

namespace {

void expect_first_seen(const std::vector<std::uint64_t>& keys) {
  const auto f = first_seen_keys(keys.data(), static_cast<Id>(keys.size()));
  std::map<std::uint64_t, std::uint32_t> number;  // key -> first-seen number
  std::vector<std::uint32_t> count, first;
  ASSERT_EQ(f.of_point.size(), keys.size());
  for (std::uint32_t i = 0; i < keys.size(); ++i) {
    const auto [it, fresh] = number.emplace(keys[i], static_cast<std::uint32_t>(count.size()));
    if (fresh) count.push_back(0), first.push_back(i);
    ++count[it->second];
    EXPECT_EQ(f.of_point[i], it->second) << "point " << i;
  }
  ASSERT_EQ(f.keys.size(), number.size());
  for (const auto& [key, s] : number) EXPECT_EQ(f.keys[s], key);
  EXPECT_EQ(f.count, count);
  EXPECT_EQ(f.first, first);
}

}  // namespace

TEST(FirstSeenKeys, MatchesAMapReference) {
  std::mt19937_64 rng(7);
  for (std::uint64_t range : {std::uint64_t{1}, std::uint64_t{5}, std::uint64_t{300}, std::uint64_t{1} << 40}) {
    for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{7}, std::size_t{1000}}) {
      std::vector<std::uint64_t> keys(n);
      for (auto& k : keys) k = rng() % range;
      expect_first_seen(keys);
    }
  }
  std::vector<std::uint64_t> low_bits_alike, high_bits_alike;
  for (std::uint64_t i = 0; i < 500; ++i) {
    low_bits_alike.push_back((i % 97) << 40);
    high_bits_alike.push_back((std::uint64_t{1} << 63) | (i % 131));
  }
  expect_first_seen(low_bits_alike);
  expect_first_seen(high_bits_alike);
}
