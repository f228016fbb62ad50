// The device layer's primitives (keymesh/device/) on the CPU device, each
// against a std:: reference: results, stability, empty inputs, 64-bit sums.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <numeric>
#include <random>
#include <vector>

#include "keymesh/device/algorithms.hpp"
#include "keymesh/device/cpu_device.hpp"
#include "keymesh/device/key_groups.hpp"

using namespace keymesh;
using device::CpuDevice;

namespace {

const CpuDevice cpu;

template <class K>
std::vector<K> random_keys(Id n, K max_key, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<K> u(0, max_key);
  std::vector<K> keys(static_cast<std::size_t>(n));
  for (auto& k : keys) k = u(rng);
  return keys;
}

struct Square {
  Id* out;
  KEYMESH_HD void operator()(Id i) const { out[i] = i * i; }
};

struct PlusD {
  double operator()(double a, double b) const { return a + b; }
};

struct ValueAt {
  const double* v;
  double operator()(Id j) const { return v[j]; }
};

}  // namespace

TEST(DevicePrimitives, ForEachVisitsEveryIndexOnce) {
  for (Id n : {Id{0}, Id{1}, Id{100000}}) {
    auto a = cpu.allocate<Id>(n);
    cpu.for_each(n, Square{a.data()});
    for (Id i = 0; i < n; ++i) ASSERT_EQ(a[i], i * i);
  }
}

TEST(DevicePrimitives, ExclusiveScanSumsIn64BitsLikeStd) {
  // Bytes summed in 64 bits (a volume's triangle counts): no wrap at 2^8 or 2^32.
  for (Id n : {Id{0}, Id{1}, Id{7}, Id{300001}}) {
    std::vector<std::uint8_t> in(static_cast<std::size_t>(n));
    std::mt19937 rng{static_cast<unsigned>(n)};
    for (auto& v : in) v = static_cast<std::uint8_t>(rng() % 6);
    std::vector<std::uint64_t> out(in.size()), ref(in.size());
    const std::uint64_t total = cpu.exclusive_scan(in.data(), out.data(), n);
    std::exclusive_scan(in.begin(), in.end(), ref.begin(), std::uint64_t{0});
    EXPECT_EQ(out, ref);
    EXPECT_EQ(total, std::accumulate(in.begin(), in.end(), std::uint64_t{0}));
  }
  std::vector<std::uint32_t> big(5, 0xF0000000u);
  std::vector<std::uint64_t> out(5);
  EXPECT_EQ(cpu.exclusive_scan(big.data(), out.data(), 5), 5ull * 0xF0000000ull);
  EXPECT_EQ(out[4], 4ull * 0xF0000000ull);
  // In place.
  std::vector<std::uint64_t> inplace = {3, 1, 4, 1, 5};
  EXPECT_EQ(cpu.exclusive_scan(inplace.data(), inplace.data(), 5), 14u);
  EXPECT_EQ(inplace, (std::vector<std::uint64_t>{0, 3, 4, 8, 9}));
}

TEST(DevicePrimitives, RadixSortIsStableLikeStdStableSort) {
  // Few distinct keys (long runs: stability shows), keys with high bits set
  // (64-bit keys), keys on fewer significant bits, 32-bit keys.
  auto check = [](auto keys, int bits) {
    using K = typename decltype(keys)::value_type;
    const Id n = static_cast<Id>(keys.size());
    std::vector<std::uint32_t> values(keys.size());
    std::iota(values.begin(), values.end(), 0u);
    std::vector<std::pair<K, std::uint32_t>> ref;
    for (Id i = 0; i < n; ++i) ref.push_back({keys[i], values[i]});
    std::stable_sort(ref.begin(), ref.end(), [](auto& a, auto& b) { return a.first < b.first; });
    cpu.sort_pairs(keys.data(), values.data(), n, bits);
    for (Id i = 0; i < n; ++i) {
      ASSERT_EQ(keys[i], ref[i].first) << i;
      ASSERT_EQ(values[i], ref[i].second) << i;
    }
  };
  check(random_keys<std::uint64_t>(200000, 40, 1), 64);
  check(random_keys<std::uint64_t>(100000, ~std::uint64_t{0}, 2), 64);
  std::vector<std::uint64_t> high = random_keys<std::uint64_t>(50000, 3, 3);
  for (auto& k : high) k = (k << 61) | 5;  // only the top bits differ
  check(high, 64);
  check(random_keys<std::uint64_t>(70000, (std::uint64_t{1} << 37) - 1, 4), 37);
  check(random_keys<std::uint32_t>(90000, 1000, 5), 10);
  check(std::vector<std::uint64_t>{}, 64);
  check(std::vector<std::uint64_t>{42}, 64);
}

TEST(DevicePrimitives, RunLengthFindsEveryRun) {
  std::vector<std::uint64_t> sorted = random_keys<std::uint64_t>(100000, 5000, 6);
  std::sort(sorted.begin(), sorted.end());
  const Id n = static_cast<Id>(sorted.size());
  std::vector<Id> run_of(sorted.size());
  const auto runs = device::run_length(cpu, sorted.data(), n, run_of.data());
  std::vector<std::uint64_t> ref = sorted;
  ref.erase(std::unique(ref.begin(), ref.end()), ref.end());
  ASSERT_EQ(runs.count, static_cast<Id>(ref.size()));
  for (Id g = 0; g < runs.count; ++g) {
    EXPECT_EQ(runs.unique_keys[g], ref[g]);
    const auto lo = std::lower_bound(sorted.begin(), sorted.end(), ref[g]) - sorted.begin();
    const auto hi = std::upper_bound(sorted.begin(), sorted.end(), ref[g]) - sorted.begin();
    ASSERT_EQ(runs.offsets[g], lo);
    ASSERT_EQ(runs.offsets[g + 1], hi);
  }
  for (Id i = 0; i < n; ++i) ASSERT_EQ(runs.unique_keys[run_of[i]], sorted[i]);
  const auto none = device::run_length(cpu, sorted.data(), 0);
  EXPECT_EQ(none.count, 0);
  ASSERT_EQ(none.offsets.size(), 1u);
  EXPECT_EQ(none.offsets[0], 0);
}

TEST(DevicePrimitives, GatherAndScatterInvertAPermutation) {
  const Id n = 12345;
  std::vector<std::uint32_t> perm(n);
  std::iota(perm.begin(), perm.end(), 0u);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(9));
  std::vector<double> in(n), gathered(n), back(n);
  for (Id i = 0; i < n; ++i) in[i] = 0.5 * double(i) - 7;
  device::gather(cpu, in.data(), perm.data(), n, gathered.data());
  for (Id i = 0; i < n; ++i) ASSERT_EQ(gathered[i], in[perm[i]]);
  device::scatter(cpu, gathered.data(), perm.data(), n, back.data());
  EXPECT_EQ(back, in);
  std::vector<int> filled(10);
  device::fill(cpu, filled.data(), 10, 3);
  EXPECT_EQ(filled, std::vector<int>(10, 3));
  std::vector<std::uint32_t> seq(5);
  device::iota(cpu, seq.data(), 5);
  EXPECT_EQ(seq, (std::vector<std::uint32_t>{0, 1, 2, 3, 4}));
}

TEST(DevicePrimitives, SegmentedReduceSumsLeftToRightFromTheInitialValue) {
  // Doubles whose sum depends on the order: the result must be the
  // left-to-right sum from acc's initial value, bit for bit; empty segments
  // keep it.
  std::mt19937 rng(10);
  std::uniform_real_distribution<double> u(-1e6, 1e6);
  std::vector<double> v(5000);
  for (auto& x : v) x = u(rng) * std::pow(10.0, double(rng() % 12) - 6);
  std::vector<Id> offsets = {0, 0, 1, 700, 700, 4000, 5000};
  const Id segments = static_cast<Id>(offsets.size()) - 1;
  std::vector<double> acc(segments, 0.25);
  device::segmented_reduce(cpu, offsets.data(), segments, ValueAt{v.data()}, PlusD{}, acc.data());
  for (Id s = 0; s < segments; ++s) {
    double ref = 0.25;
    for (Id j = offsets[s]; j < offsets[s + 1]; ++j) ref += v[j];
    EXPECT_EQ(acc[s], ref) << s;
  }
}

TEST(DevicePrimitives, KeyGroupsMatchAStdMapOfKeys) {
  // 64-bit keys (high bits set), pairs grouped in key order, each group's
  // pairs in pair order, the index map pointing every pair to its key.
  std::vector<std::uint64_t> keys = random_keys<std::uint64_t>(80000, 3000, 11);
  for (auto& k : keys) k = (k << 33) + 17;
  const std::vector<std::uint64_t> original = keys;
  const Id n = static_cast<Id>(keys.size());
  const auto g = device::group_keys(cpu, keys.data(), n, 64);
  std::map<std::uint64_t, std::vector<std::uint32_t>> ref;
  for (Id i = 0; i < n; ++i) ref[original[i]].push_back(static_cast<std::uint32_t>(i));
  ASSERT_EQ(g.groups, static_cast<Id>(ref.size()));
  Id at = 0;
  for (const auto& [key, pairs] : ref) {
    ASSERT_EQ(g.unique_keys[at], key);
    ASSERT_EQ(g.offsets[at + 1] - g.offsets[at], static_cast<Id>(pairs.size()));
    for (std::size_t p = 0; p < pairs.size(); ++p) ASSERT_EQ(g.sorted_pairs[g.offsets[at] + p], pairs[p]);
    ++at;
  }
  for (Id i = 0; i < n; ++i) ASSERT_EQ(g.unique_keys[g.index_map[i]], original[i]);
  std::vector<std::uint64_t> empty;
  EXPECT_EQ(device::group_keys(cpu, empty.data(), 0, 64).groups, 0);
}
