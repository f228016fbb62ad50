#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/keyreduce/reduce.hpp"
#include "keymesh/keyreduce/weld.hpp"
#include "keymesh/parallel/scan.hpp"
#include "keymesh/parallel/threads.hpp"
#include "thread_count_test.hpp"

using namespace keymesh;
using keyreduce::Order;

namespace {

// Reference grouping with std::map: group = rank of the key among distinct keys.
template <class K>
void expect_matches_reference(const std::vector<K>& keys, const keyreduce::Groups<K>& g) {
  std::map<K, std::vector<std::uint32_t>> ref;
  for (std::size_t i = 0; i < keys.size(); ++i) ref[keys[i]].push_back(static_cast<std::uint32_t>(i));
  ASSERT_EQ(g.num_groups(), static_cast<Id>(ref.size()));
  ASSERT_EQ(g.num_pairs(), static_cast<Id>(keys.size()));
  Id group = 0;
  for (const auto& [key, pairs] : ref) {
    ASSERT_EQ(g.unique_keys[group], key);
    for (auto p : pairs) ASSERT_EQ(g.index_map[p], group);
    if (g.has_order()) {
      ASSERT_EQ(g.count(group), static_cast<Id>(pairs.size()));
      for (std::size_t j = 0; j < pairs.size(); ++j) ASSERT_EQ(g.order[g.offsets[group] + j], pairs[j]);
    }
    ++group;
  }
}

template <class K>
void expect_both_plans(const std::vector<K>& keys, K range) {
  const Id n = static_cast<Id>(keys.size());
  expect_matches_reference(keys, keyreduce::partition_sort(keys.data(), n, int(sizeof(K) * 8)));
  expect_matches_reference(keys, keyreduce::partition_dense(keys.data(), n, range));
  expect_matches_reference(keys, keyreduce::partition_sort(keys.data(), n, int(sizeof(K) * 8), Order::Skip));
  expect_matches_reference(keys, keyreduce::partition_dense(keys.data(), n, range, Order::Skip));
  expect_matches_reference(keys, keyreduce::partition_runs(keys.data(), n));
  expect_matches_reference(keys, keyreduce::partition_runs(keys.data(), n, Order::Skip));
}

// A weld over keys < range (bits of them), with the pair order built.
template <class K>
keyreduce::WeldSpec<K> weld_spec(keyreduce::WeldPlan plan, K range, int bits) {
  keyreduce::WeldSpec<K> spec;
  spec.plan = plan;
  spec.key_range = range;
  spec.key_bits = bits;
  spec.order = Order::Build;
  return spec;
}

class KeyReduceThreads : public keymesh::tests::ThreadCountTest {};

}  // namespace

TEST_P(KeyReduceThreads, Empty) { expect_both_plans<std::uint64_t>({}, 10); }

TEST_P(KeyReduceThreads, OneElement) { expect_both_plans<std::uint32_t>({5u}, 6u); }

TEST_P(KeyReduceThreads, AllKeysEqual) { expect_both_plans<std::uint64_t>(std::vector<std::uint64_t>(200000, 3), 4); }

TEST_P(KeyReduceThreads, KeysAtTopOfRange) {
  // Sort plan: keys at the top of the 32- and 64-bit ranges.
  std::vector<std::uint32_t> keys;
  for (int i = 0; i < 100000; ++i) keys.push_back(0xFFFFFFFFu - static_cast<std::uint32_t>(i % 3));
  expect_matches_reference(keys, keyreduce::partition_sort(keys.data(), Id(keys.size()), 32));
  std::vector<std::uint64_t> wide;
  for (int i = 0; i < 100000; ++i) wide.push_back(~std::uint64_t{0} - static_cast<std::uint64_t>(i % 5));
  expect_matches_reference(wide, keyreduce::partition_sort(wide.data(), Id(wide.size()), 64));
  // Dense plan: keys at the top of the declared range, including its last key
  // and the last bit of a 64-bit word.
  const std::uint32_t range = 1u << 20;
  std::vector<std::uint32_t> top;
  for (int i = 0; i < 100000; ++i) top.push_back(range - 1 - static_cast<std::uint32_t>(i % 70));
  expect_both_plans<std::uint32_t>(top, range);
}

TEST_P(KeyReduceThreads, RandomKeysLikeAContour) {
  std::mt19937_64 rng(7);
  std::vector<std::uint64_t> keys(300000);
  for (auto& k : keys) k = rng() % 90000;  // ~3.3 pairs per key
  expect_both_plans<std::uint64_t>(keys, 90000);
}

// The merge plan on what it is for: pieces' increasing keys, concatenated,
// sharing keys across pieces (and within none); an odd number of runs, one
// empty, so a run is left over in a round.
TEST(KeyReduceRuns, MergesIncreasingRunsLikeTheSortPlan) {
  std::mt19937_64 rng(11);
  std::vector<std::uint64_t> keys;
  for (int piece = 0; piece < 7; ++piece) {
    std::vector<std::uint64_t> run;
    for (int j = 0, count = piece == 3 ? 0 : 500 + 300 * piece; j < count; ++j) run.push_back(rng() % 4000);
    std::sort(run.begin(), run.end());
    run.erase(std::unique(run.begin(), run.end()), run.end());
    keys.insert(keys.end(), run.begin(), run.end());
  }
  const auto g = keyreduce::partition_runs(keys.data(), Id(keys.size()));
  ASSERT_LT(g.num_groups(), Id(keys.size()));  // the pieces share keys
  expect_matches_reference(keys, g);
  expect_matches_reference(keys, keyreduce::partition_runs(keys.data(), Id(keys.size()), Order::Skip));
}

TEST(KeyReduceRuns, SortedKeysAndDescendingKeys) {
  std::vector<std::uint32_t> up{1, 1, 2, 5, 5, 5, 9};
  expect_matches_reference(up, keyreduce::partition_runs(up.data(), Id(up.size())));
  std::vector<std::uint32_t> down{9, 7, 7, 4, 2, 2, 0};  // every key its own run but the repeats
  expect_matches_reference(down, keyreduce::partition_runs(down.data(), Id(down.size())));
}

TEST_P(KeyReduceThreads, ReduceAveragesInPairOrder) {
  std::mt19937 rng(11);
  std::vector<std::uint32_t> keys(100000);
  std::vector<double> values(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    keys[i] = rng() % 1000;
    values[i] = std::uniform_real_distribution<double>(-1, 1)(rng);
  }
  for (auto plan : {keyreduce::Plan::Sort, keyreduce::Plan::Dense}) {
    const auto g = plan == keyreduce::Plan::Sort
                       ? keyreduce::partition_sort(keys.data(), Id(keys.size()), 10)
                       : keyreduce::partition_dense(keys.data(), Id(keys.size()), 1000u);
    std::vector<double> mean(g.num_groups());
    keyreduce::reduce_values(
        g, values.data(), [](double a, double b) { return a + b; },
        [](double sum, Id count) { return sum / double(count); }, mean.data());
    // Reference: the same left-to-right sums over increasing pair index.
    std::map<std::uint32_t, std::pair<double, int>> ref;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      auto& [s, c] = ref[keys[i]];
      s = c == 0 ? values[i] : s + values[i];
      ++c;
    }
    Id group = 0;
    for (const auto& [key, sc] : ref) ASSERT_EQ(mean[group++], sc.first / sc.second) << "key " << key;
  }
}

TEST_P(KeyReduceThreads, MergeCanRunInPieces) {
  // merge is associative: reducing two halves and merging the partial
  // results gives the same integer sums as one reduction (what distributed
  // and streamed KEY-REDUCE rely on).
  std::vector<std::uint64_t> keys, values;
  for (int i = 0; i < 50000; ++i) {
    keys.push_back(static_cast<std::uint64_t>((i * 7919) % 4001));
    values.push_back(static_cast<std::uint64_t>(i));
  }
  auto sum_by_key = [](const std::vector<std::uint64_t>& k, const std::vector<std::uint64_t>& v) {
    const auto g = keyreduce::partition_sort(k.data(), Id(k.size()), 64);
    std::vector<std::uint64_t> out(g.num_groups());
    keyreduce::reduce_values(g, v.data(), [](auto a, auto b) { return a + b; }, [](auto s, Id) { return s; }, out.data());
    std::map<std::uint64_t, std::uint64_t> m;
    for (Id i = 0; i < g.num_groups(); ++i) m[g.unique_keys[i]] = out[i];
    return m;
  };
  const auto whole = sum_by_key(keys, values);
  const std::size_t half = keys.size() / 2;
  auto a = sum_by_key({keys.begin(), keys.begin() + half}, {values.begin(), values.begin() + half});
  const auto b = sum_by_key({keys.begin() + half, keys.end()}, {values.begin() + half, values.end()});
  for (const auto& [k, v] : b) a[k] += v;
  EXPECT_EQ(a, whole);
}

TEST_P(KeyReduceThreads, ReduceBlockedScattersInAFixedOrder) {
  // Blocks of 1000 pairs whose keys come from a window that overlaps only the
  // next block's window (the locality a marching cubes soup has by slabs).
  std::mt19937 rng(5);
  const Id blocks = 37;
  std::vector<std::uint32_t> keys;
  std::vector<double> values;
  std::vector<Id> begin;
  for (Id b = 0; b < blocks; ++b) {
    begin.push_back(Id(keys.size()));
    const Id n = b == 3 ? 0 : 1000;  // an empty block too
    for (Id i = 0; i < n; ++i) {
      keys.push_back(static_cast<std::uint32_t>(b * 100 + Id(rng() % 150)));
      values.push_back(std::uniform_real_distribution<double>(-1, 1)(rng));
    }
  }
  begin.push_back(Id(keys.size()));
  const auto g = keyreduce::partition_dense(keys.data(), Id(keys.size()), std::uint32_t(blocks * 100 + 50));
  std::vector<double> sum(g.num_groups());
  keyreduce::reduce_blocked(g.index_map.data(), begin.data(), blocks, 1, [&](Id i) { return values[i]; },
                            [](double a, double b) { return a + b; }, 0.0, sum.data(), g.num_groups());
  // Reference: per key, the even block's values in pair order, then the odd block's.
  std::map<std::uint32_t, double> ref;
  for (int parity = 0; parity < 2; ++parity)
    for (Id b = parity; b < blocks; b += 2)
      for (Id i = begin[b]; i < begin[b + 1]; ++i) ref[keys[i]] += values[i];
  ASSERT_EQ(Id(ref.size()), g.num_groups());
  Id group = 0;
  for (const auto& [key, s] : ref) {
    ASSERT_EQ(g.unique_keys[group], key);
    ASSERT_EQ(sum[group++], s) << "key " << key;  // bit-identical, at any thread count
  }
}

TEST_P(KeyReduceThreads, DenseRefusesKeysOutsideRange) {
  std::vector<std::uint32_t> keys{1, 2, 10};
  EXPECT_THROW(keyreduce::partition_dense(keys.data(), 3, 10u), InputError);
}

INSTANTIATE_TEST_SUITE_P(Threads, KeyReduceThreads, ::testing::Values(1, 2, 4));

TEST(ExclusiveScan, MatchesSerialAndReturnsTotal) {
  for (int threads : {1, 2, 3}) {
    parallel::set_thread_count(threads);
    for (Id n : {0, 1, 7, 100000, 300001}) {
      std::vector<std::uint32_t> in(n);
      for (Id i = 0; i < n; ++i) in[i] = static_cast<std::uint32_t>((i * 31) % 7);
      std::vector<std::uint64_t> out(n);
      const auto total = parallel::exclusive_scan(in.data(), out.data(), n);
      std::uint64_t s = 0;
      for (Id i = 0; i < n; ++i) {
        ASSERT_EQ(out[i], s);
        s += in[i];
      }
      EXPECT_EQ(total, s);
    }
  }
  parallel::set_thread_count(0);
}

// The weld layer: the dense and sort plans give the reference grouping; the
// by-position plan (VERTEX-WELD) groups pairs whose positions are equal,
// which here are a function of the key alone, so it finds the same groups up
// to renumbering; every plan's `first` is the smallest pair of its group.
TEST(Weld, ThreePlansGroupAlike) {
  std::mt19937 rng(5);
  std::vector<std::uint32_t> keys(20000);
  for (auto& k : keys) k = std::uniform_int_distribution<std::uint32_t>(0, 2999)(rng);
  auto position = [&](Id i, float* xyz) {
    const std::uint32_t k = keys[static_cast<std::size_t>(i)];
    xyz[0] = static_cast<float>(k % 17);
    xyz[1] = static_cast<float>(k / 17);
    xyz[2] = 0.5f;
  };
  for (auto plan : {keyreduce::WeldPlan::Dense, keyreduce::WeldPlan::Sort, keyreduce::WeldPlan::ByPosition}) {
    const auto spec = weld_spec<std::uint32_t>(plan, 3000, 12);
    Array<float> points;
    std::vector<std::uint32_t> first;
    const auto g = keyreduce::weld(keys.data(), static_cast<Id>(keys.size()), spec, position, {&points, &first});
    if (plan != keyreduce::WeldPlan::ByPosition) {
      expect_matches_reference(keys, g);
      EXPECT_TRUE(points.empty());
    } else {
      ASSERT_EQ(static_cast<Id>(points.size()), 3 * g.num_groups());
      // Same partition: pairs share a group exactly when they share a key.
      std::map<std::uint32_t, std::uint32_t> group_of_key;
      for (std::size_t i = 0; i < keys.size(); ++i) {
        const auto [it, fresh] = group_of_key.emplace(keys[i], g.index_map[i]);
        ASSERT_EQ(it->second, g.index_map[i]);
        ASSERT_EQ(g.unique_keys[g.index_map[i]], keys[i]);
      }
      EXPECT_EQ(static_cast<Id>(group_of_key.size()), g.num_groups());
    }
    ASSERT_EQ(static_cast<Id>(first.size()), g.num_groups());
    std::vector<std::uint32_t> smallest(first.size(), UINT32_MAX);
    for (std::size_t i = 0; i < keys.size(); ++i)
      smallest[g.index_map[i]] = std::min(smallest[g.index_map[i]], static_cast<std::uint32_t>(i));
    EXPECT_EQ(first, smallest);
  }
}

// Keys given up to the weld: the sort plan sorts them in their own storage
// (the caller's vector is left empty) and groups them as the reference does;
// the other plans leave them to `position`.
TEST(Weld, GivenUpKeysGroupAlike) {
  std::mt19937 rng(9);
  std::vector<std::uint64_t> reference(50000);
  for (auto& k : reference) k = std::uniform_int_distribution<std::uint64_t>(0, (std::uint64_t{1} << 40) - 1)(rng) % 7001;
  for (auto plan : {keyreduce::WeldPlan::Sort, keyreduce::WeldPlan::Dense, keyreduce::WeldPlan::ByPosition}) {
    const auto spec = weld_spec<std::uint64_t>(plan, 7001, 13);
    std::vector<std::uint64_t> keys = reference;
    auto position = [&](Id i, float* xyz) {
      xyz[0] = static_cast<float>(keys.at(static_cast<std::size_t>(i)));
      xyz[1] = xyz[2] = 0;
    };
    std::vector<std::uint32_t> first;
    const auto g = keyreduce::weld(std::move(keys), spec, position, {nullptr, &first});
    if (plan != keyreduce::WeldPlan::ByPosition) expect_matches_reference(reference, g);
    EXPECT_EQ(keys.empty(), plan == keyreduce::WeldPlan::Sort);
    ASSERT_EQ(static_cast<Id>(first.size()), g.num_groups());
    for (std::size_t i = 0; i < reference.size(); ++i) EXPECT_LE(first[g.index_map[i]], i);
  }
}
