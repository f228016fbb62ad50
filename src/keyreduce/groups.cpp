#include "keymesh/keyreduce/groups.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <limits>
#include <memory>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/run_length.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh::keyreduce {

namespace {

void check_pair_count(Id n) {
  if (n < 0 || n > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("KEY-REDUCE: " + std::to_string(n) +
                     " keyed pairs exceed the 32-bit index map (at most 4294967295)");
}

}  // namespace

template <class K>
Groups<K> partition_sort(const K* keys, Id n, int significant_bits, Order order) {
  check_pair_count(n);
  Groups<K> groups;
  std::vector<K> sorted(keys, keys + n);
  std::vector<std::uint32_t> perm(n);
  parallel::for_each(n, [&](Id i) { perm[i] = static_cast<std::uint32_t>(i); });
  parallel::sort_pairs(sorted, perm, significant_bits);
  parallel::run_length(sorted.data(), n, groups.unique_keys, groups.offsets);
  groups.index_map.resize(n);
  const Id g_count = groups.num_groups();
  auto* index_map = groups.index_map.data();
  const auto* offsets = groups.offsets.data();
  parallel::for_each(g_count, [&](Id g) {
    for (Id j = offsets[g]; j < offsets[g + 1]; ++j) index_map[perm[j]] = static_cast<std::uint32_t>(g);
  }, 1024);
  if (order == Order::Build) {
    groups.order = std::move(perm);  // stable sort: increasing pair index within a group
  } else {
    groups.offsets.clear();
  }
  return groups;
}

template <class K>
Groups<K> partition_dense(const K* keys, Id n, K key_range, Order order) {
  check_pair_count(n);
  Groups<K> groups;
  const Id words = static_cast<Id>((static_cast<std::uint64_t>(key_range) + 63) / 64);
  // One bit per possible key. Zeroed in parallel so that both the work and
  // the first-touch page faults are shared by the threads.
  std::unique_ptr<std::uint64_t[]> present(new std::uint64_t[static_cast<std::size_t>(words)]);
  parallel::for_each(words, [&](Id w) { present[w] = 0; }, 1 << 16);
  // Mark present keys. Most keys repeat (a contour point is shared by ~6
  // triangles), so test before the atomic OR: only the first sighting writes.
  bool out_of_range = false;
  parallel::for_each(n, [&](Id i) {
    const K k = keys[i];
    if (k >= key_range) {
      out_of_range = true;
      return;
    }
    const std::uint64_t bit = std::uint64_t{1} << (k & 63);
    std::atomic_ref<std::uint64_t> word(present[k >> 6]);
    if (!(word.load(std::memory_order_relaxed) & bit)) word.fetch_or(bit, std::memory_order_relaxed);
  });
  if (out_of_range)
    throw InputError("KEY-REDUCE dense plan: a key is outside the declared range [0, " +
                     std::to_string(static_cast<std::uint64_t>(key_range)) + ")");
  // Rank of the first key of every block of kBlockWords words: a prefix count
  // of present keys (a rank per block rather than per word keeps this array
  // small). It fits 32 bits because there are no more groups than pairs.
  constexpr Id kBlockWords = 8;
  const Id blocks = (words + kBlockWords - 1) / kBlockWords;
  std::vector<std::uint32_t> block_rank(blocks + 1);
  parallel::for_each(blocks, [&](Id b) {
    std::uint32_t c = 0;
    for (Id w = b * kBlockWords, e = std::min(words, w + kBlockWords); w < e; ++w)
      c += static_cast<std::uint32_t>(std::popcount(present[w]));
    block_rank[b] = c;
  });
  block_rank[blocks] = 0;
  const Id g_count = static_cast<Id>(parallel::exclusive_scan(block_rank.data(), block_rank.data(), blocks + 1));
  groups.unique_keys.resize(g_count);
  auto* unique = groups.unique_keys.data();
  parallel::for_each(blocks, [&](Id b) {
    std::uint32_t r = block_rank[b];
    for (Id w = b * kBlockWords, e = std::min(words, w + kBlockWords); w < e; ++w) {
      std::uint64_t bits = present[w];
      while (bits) {
        const int bit = std::countr_zero(bits);
        unique[r++] = static_cast<K>(static_cast<std::uint64_t>(w) * 64 + static_cast<std::uint64_t>(bit));
        bits &= bits - 1;
      }
    }
  });
  groups.index_map.resize(n);
  auto* index_map = groups.index_map.data();
  parallel::for_each(n, [&](Id i) {
    const K k = keys[i];
    const Id w = static_cast<Id>(k >> 6);
    std::uint32_t r = block_rank[w / kBlockWords];
    for (Id v = w - w % kBlockWords; v < w; ++v) r += static_cast<std::uint32_t>(std::popcount(present[v]));
    const std::uint64_t below = present[w] & ((std::uint64_t{1} << (k & 63)) - 1);
    index_map[i] = r + static_cast<std::uint32_t>(std::popcount(below));
  });
  if (order == Order::Build) build_order(groups);
  return groups;
}

template <class K>
void build_order(Groups<K>& groups) {
  const Id n = groups.num_pairs();
  const Id g_count = groups.num_groups();
  const auto* index_map = groups.index_map.data();
  // Counting sort by group: counts by atomic increments (the totals do not
  // depend on the schedule), slots by atomic fetch-add, then each group's few
  // pair indices sorted so the order is increasing, whatever the schedule.
  std::vector<Id> offsets(g_count + 1, 0);
  parallel::for_each(n, [&](Id i) {
    std::atomic_ref<Id>(offsets[index_map[i]]).fetch_add(1, std::memory_order_relaxed);
  });
  parallel::exclusive_scan(offsets.data(), offsets.data(), g_count + 1);
  std::vector<Id> cursor(offsets.begin(), offsets.end() - 1);
  std::vector<std::uint32_t> order(n);
  parallel::for_each(n, [&](Id i) {
    const Id at = std::atomic_ref<Id>(cursor[index_map[i]]).fetch_add(1, std::memory_order_relaxed);
    order[at] = static_cast<std::uint32_t>(i);
  });
  parallel::for_each_dynamic(g_count, [&](Id g) {
    auto* b = order.data() + offsets[g];
    auto* e = order.data() + offsets[g + 1];
    if (e - b <= 32) {
      for (auto* p = b + 1; p < e; ++p)  // insertion sort: groups are small
        for (auto* q = p; q > b && q[-1] > q[0]; --q) std::swap(q[-1], q[0]);
    } else {
      std::sort(b, e);
    }
  }, 4096);
  groups.offsets = std::move(offsets);
  groups.order = std::move(order);
}

template Groups<std::uint32_t> partition_sort(const std::uint32_t*, Id, int, Order);
template Groups<std::uint64_t> partition_sort(const std::uint64_t*, Id, int, Order);
template Groups<std::uint32_t> partition_dense(const std::uint32_t*, Id, std::uint32_t, Order);
template Groups<std::uint64_t> partition_dense(const std::uint64_t*, Id, std::uint64_t, Order);
template void build_order(Groups<std::uint32_t>&);
template void build_order(Groups<std::uint64_t>&);

}  // namespace keymesh::keyreduce
