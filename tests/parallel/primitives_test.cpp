#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/run_length.hpp"
#include "thread_count_test.hpp"

namespace kp = keymesh::parallel;
using keymesh::Id;

namespace {

class PrimitivesThreads : public keymesh::tests::ThreadCountTest {};

// Reference run-length encoding, written the obvious serial way.
template <class K>
void reference_runs(const std::vector<K>& sorted, std::vector<K>& keys, std::vector<Id>& offsets) {
  keys.clear();
  offsets.clear();
  for (std::size_t i = 0; i < sorted.size(); ++i)
    if (i == 0 || sorted[i] != sorted[i - 1]) {
      keys.push_back(sorted[i]);
      offsets.push_back(static_cast<Id>(i));
    }
  offsets.push_back(static_cast<Id>(sorted.size()));
}

}  // namespace

TEST_P(PrimitivesThreads, RunLengthMatchesReference) {
  std::mt19937_64 rng(5);
  std::vector<std::vector<std::uint64_t>> inputs = {
      {}, {9}, std::vector<std::uint64_t>(100000, 4), {~std::uint64_t{0}, ~std::uint64_t{0}}};
  std::vector<std::uint64_t> random(200000);
  for (auto& k : random) k = rng() % 5000;
  std::sort(random.begin(), random.end());
  inputs.push_back(random);
  for (const auto& in : inputs) {
    std::vector<std::uint64_t> keys, ref_keys;
    std::vector<Id> offsets, ref_offsets;
    kp::run_length(in.data(), static_cast<Id>(in.size()), keys, offsets);
    reference_runs(in, ref_keys, ref_offsets);
    EXPECT_EQ(keys, ref_keys);
    EXPECT_EQ(offsets, ref_offsets);
  }
}

TEST_P(PrimitivesThreads, LowerBoundMatchesStd) {
  std::mt19937 rng(6);
  std::vector<std::uint32_t> sorted(50000);
  for (auto& k : sorted) k = rng() % 100000;
  std::sort(sorted.begin(), sorted.end());
  std::vector<std::uint32_t> queries = {0, 0xFFFFFFFFu, sorted.front(), sorted.back()};
  for (int i = 0; i < 20000; ++i) queries.push_back(rng() % 100001);
  std::vector<Id> got(queries.size());
  kp::lower_bound(sorted.data(), static_cast<Id>(sorted.size()), queries.data(), static_cast<Id>(queries.size()),
                  got.data());
  for (std::size_t i = 0; i < queries.size(); ++i)
    ASSERT_EQ(got[i], std::lower_bound(sorted.begin(), sorted.end(), queries[i]) - sorted.begin()) << queries[i];
  // Empty sorted range: every query lands at 0.
  std::vector<Id> none(3, 7);
  kp::lower_bound(sorted.data(), 0, queries.data(), 3, none.data());
  EXPECT_EQ(none, std::vector<Id>(3, 0));
}

TEST_P(PrimitivesThreads, GatherScatterAreInverse) {
  const Id n = 123457;
  std::vector<std::uint32_t> perm(n);
  for (Id i = 0; i < n; ++i) perm[i] = static_cast<std::uint32_t>(i);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(8));
  std::vector<double> values(n), gathered(n), back(n);
  for (Id i = 0; i < n; ++i) values[i] = 0.5 * static_cast<double>(i);
  kp::gather(values.data(), perm.data(), n, gathered.data());
  for (Id i = 0; i < n; ++i) ASSERT_EQ(gathered[i], values[perm[i]]);
  kp::scatter(gathered.data(), perm.data(), n, back.data());
  EXPECT_EQ(back, values);
}

TEST_P(PrimitivesThreads, ForEachVisitsEveryIndexOnce) {
  for (Id n : {Id{0}, Id{1}, Id{4095}, Id{100003}}) {
    std::vector<int> hits(n, 0);
    kp::for_each(n, [&](Id i) { ++hits[i]; });
    EXPECT_EQ(std::count(hits.begin(), hits.end(), 1), n);
    std::vector<int> dyn(n, 0);
    kp::for_each_dynamic(n, [&](Id i) { ++dyn[i]; });
    EXPECT_EQ(std::count(dyn.begin(), dyn.end(), 1), n);
  }
}

TEST_P(PrimitivesThreads, ChunksDependOnlyOnTheRange) {
  // The same (n, chunks) always gives the same bounds, covering [0, n).
  const Id n = 1000003;
  for (int chunks : {1, 2, 3, 7}) {
    Id covered = 0;
    for (int c = 0; c < chunks; ++c) {
      EXPECT_EQ(kp::chunk_begin(n, chunks, c), covered);
      covered = kp::chunk_begin(n, chunks, c + 1);
    }
    EXPECT_EQ(covered, n);
  }
}

INSTANTIATE_TEST_SUITE_P(Threads, PrimitivesThreads, ::testing::Values(1, 2, 3));
