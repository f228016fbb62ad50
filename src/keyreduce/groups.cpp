#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/keyreduce/pair_count.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/run_length.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh::keyreduce {

void check_pair_count(Id n) {
  if (n < 0 || n > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("KEY-REDUCE: " + std::to_string(n) +
                     " keyed pairs exceed the 32-bit index map (at most 4294967295)");
}

template <class K>
Groups<K> partition_sort(const K* keys, Id n, int significant_bits, Order order) {
  check_pair_count(n);
  return partition_sort(std::vector<K>(keys, keys + n), significant_bits, order);
}

template <class K>
Groups<K> partition_sort(std::vector<K>&& keys, int significant_bits, Order order) {
  const Id n = static_cast<Id>(keys.size());
  check_pair_count(n);
  Groups<K> groups;
  std::vector<K> sorted = std::move(keys);
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

namespace {

// The pairs (key, pair) stably sorted by key: the increasing runs of `keys`
// merged in rounds, each merging neighbouring runs into the other buffer.
template <class K>
std::vector<std::pair<K, std::uint32_t>> merge_runs(const K* keys, Id n) {
  std::vector<std::pair<K, std::uint32_t>> pairs(static_cast<std::size_t>(n)), merged(pairs.size());
  std::vector<std::size_t> bounds{0};
  for (Id i = 0; i < n; ++i) {
    if (i > 0 && keys[i] < keys[i - 1]) bounds.push_back(static_cast<std::size_t>(i));
    pairs[static_cast<std::size_t>(i)] = {keys[i], static_cast<std::uint32_t>(i)};
  }
  bounds.push_back(pairs.size());
  const auto by_key = [](const auto& a, const auto& b) { return a.first < b.first; };
  while (bounds.size() > 2) {
    std::vector<std::size_t> next{0};
    for (std::size_t r = 0; r + 1 < bounds.size(); r += 2) {
      const std::size_t b = bounds[r], m = bounds[r + 1], e = r + 2 < bounds.size() ? bounds[r + 2] : m;
      std::merge(pairs.begin() + b, pairs.begin() + m, pairs.begin() + m, pairs.begin() + e, merged.begin() + b, by_key);
      next.push_back(e);
    }
    pairs.swap(merged);
    bounds.swap(next);
  }
  return pairs;
}

}  // namespace

template <class K>
Groups<K> partition_runs(const K* keys, Id n, Order order) {
  check_pair_count(n);
  Groups<K> groups;
  groups.index_map.resize(n);
  bool sorted = true;
  for (Id i = 1; i < n && sorted; ++i) sorted = !(keys[i] < keys[i - 1]);
  std::vector<std::pair<K, std::uint32_t>> merged;
  if (!sorted) merged = merge_runs(keys, n);
  if (order == Order::Build) groups.order.resize(static_cast<std::size_t>(n));
  for (Id i = 0; i < n; ++i) {
    const K key = sorted ? keys[i] : merged[static_cast<std::size_t>(i)].first;
    const std::uint32_t pair = sorted ? static_cast<std::uint32_t>(i) : merged[static_cast<std::size_t>(i)].second;
    if (groups.unique_keys.empty() || key != groups.unique_keys.back()) {
      groups.unique_keys.push_back(key);
      groups.offsets.push_back(i);
    }
    groups.index_map[pair] = static_cast<std::uint32_t>(groups.unique_keys.size() - 1);
    if (order == Order::Build) groups.order[static_cast<std::size_t>(i)] = pair;
  }
  groups.offsets.push_back(n);
  if (order == Order::Skip) groups.offsets.clear();
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
  std::vector<Id> offsets(g_count + 1, 0);
  std::vector<std::uint32_t> order(n);
  // Stable counting sort by group over fixed contiguous chunks of pairs: a
  // histogram per chunk, then every (chunk, group) gets its slot range in
  // chunk order, so each group lists its pairs in increasing index with no
  // atomics and no per-group sorting. The per-chunk histograms cost
  // chunks x groups counters: when that is large next to the pairs, fewer
  // chunks are used (the result is the same for any chunk count).
  int chunks = parallel::chunk_count(n, 1 << 16);
  while (chunks > 1 && static_cast<Id>(chunks) * g_count > 2 * n) --chunks;
  std::vector<std::uint32_t> hist(static_cast<std::size_t>(chunks) * static_cast<std::size_t>(g_count));
  parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
    std::uint32_t* h = hist.data() + static_cast<std::size_t>(c) * static_cast<std::size_t>(g_count);
    std::fill(h, h + g_count, 0u);
    for (Id i = b; i < e; ++i) ++h[index_map[i]];
  });
  // Per group: its total count, and each chunk's start within the group.
  parallel::for_each(g_count, [&](Id g) {
    std::uint32_t running = 0;
    for (int c = 0; c < chunks; ++c) {
      std::uint32_t& h = hist[static_cast<std::size_t>(c) * static_cast<std::size_t>(g_count) + static_cast<std::size_t>(g)];
      const std::uint32_t count = h;
      h = running;
      running += count;
    }
    offsets[g] = running;
  });
  offsets[g_count] = 0;
  parallel::exclusive_scan(offsets.data(), offsets.data(), g_count + 1);
  parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
    std::uint32_t* h = hist.data() + static_cast<std::size_t>(c) * static_cast<std::size_t>(g_count);
    for (Id i = b; i < e; ++i) {
      const std::uint32_t g = index_map[i];
      order[static_cast<std::size_t>(offsets[g] + h[g]++)] = static_cast<std::uint32_t>(i);
    }
  });
  groups.offsets = std::move(offsets);
  groups.order = std::move(order);
}

template Groups<std::uint32_t> partition_sort(const std::uint32_t*, Id, int, Order);
template Groups<std::uint64_t> partition_sort(const std::uint64_t*, Id, int, Order);
template Groups<std::uint32_t> partition_sort(std::vector<std::uint32_t>&&, int, Order);
template Groups<std::uint64_t> partition_sort(std::vector<std::uint64_t>&&, int, Order);
template Groups<std::uint32_t> partition_runs(const std::uint32_t*, Id, Order);
template Groups<std::uint64_t> partition_runs(const std::uint64_t*, Id, Order);
template Groups<std::uint32_t> partition_dense(const std::uint32_t*, Id, std::uint32_t, Order);
template Groups<std::uint64_t> partition_dense(const std::uint64_t*, Id, std::uint64_t, Order);
template void build_order(Groups<std::uint32_t>&);
template void build_order(Groups<std::uint64_t>&);

}  // namespace keymesh::keyreduce
