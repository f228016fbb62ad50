#pragma once
// Stable LSD radix sort of (key, value) pairs with unsigned 32- or 64-bit
// keys. `significant_bits` says how many low key bits can be non-zero, so a
// key known to fit in 23 bits costs three passes of 8 bits, not eight;
// digits are at most 11 bits wide (48 bits: five passes of 10). Passes in
// which every key has the same digit are skipped. Each pass histograms fixed
// contiguous chunks and scatters them in chunk order: the result is the
// stable order, independent of the thread count.
#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

#include "keymesh/parallel/bits_needed.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::parallel {

// The stable order of the pairs by their keys' low `significant_bits`
// (the order the passes make), by comparisons, in place.
template <class K, class V>
void stable_sort_pairs_by_low_bits(K* keys, V* values, Id n, int significant_bits) {
  const K mask = significant_bits >= int(sizeof(K) * 8) ? ~K{0} : static_cast<K>((K{1} << significant_bits) - 1);
  std::vector<std::pair<K, V>> pairs(static_cast<std::size_t>(n));
  for (Id i = 0; i < n; ++i) pairs[static_cast<std::size_t>(i)] = {keys[i], values[i]};
  std::stable_sort(pairs.begin(), pairs.end(), [mask](const auto& a, const auto& b) { return (a.first & mask) < (b.first & mask); });
  for (Id i = 0; i < n; ++i) keys[i] = pairs[static_cast<std::size_t>(i)].first, values[i] = pairs[static_cast<std::size_t>(i)].second;
}

// The passes of sort_pairs over caller-owned arrays: the pairs start in
// (keys, values) and end where the return value says (false: there; true:
// in (keys_tmp, values_tmp), after an odd number of passes ran).
template <class K, class V>
bool sort_pairs_passes(K* keys, V* values, K* keys_tmp, V* values_tmp, Id n, int significant_bits) {
  static_assert(std::is_unsigned_v<K>, "radix sort keys are unsigned integers");
  if (n <= 1) return false;
  if (significant_bits > int(sizeof(K) * 8)) significant_bits = int(sizeof(K) * 8);
  if (significant_bits <= 0) return false;
  // Digits of at most kMaxDigitBits, as few passes as that allows, the bits
  // spread evenly over them (48 bits: 5 passes of 10, not 6 of 8).
  constexpr int kMaxDigitBits = 11;
  const int passes = (significant_bits + kMaxDigitBits - 1) / kMaxDigitBits;
  const int digit_bits = (significant_bits + passes - 1) / passes;
  const Id buckets = Id{1} << digit_bits;
  const K mask = static_cast<K>(buckets - 1);
  // Few pairs (a weld of one chunk's piece): every pass zeroes, scans and
  // offsets 2^digit_bits buckets, more work than comparing the pairs; the
  // comparison sort makes the same stable order.
  if (n * 8 < passes * buckets) {
    stable_sort_pairs_by_low_bits(keys, values, n, significant_bits);
    return false;
  }

  const int chunks = chunk_count(n, 1 << 15);
  std::vector<Id> hist_store(static_cast<std::size_t>(chunks * buckets));
  auto hist = [&](int c) { return hist_store.data() + c * buckets; };

  K* src_k = keys;
  V* src_v = values;
  K* dst_k = keys_tmp;
  V* dst_v = values_tmp;
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = pass * digit_bits;
    for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
      Id* h = hist(c);
      std::fill(h, h + buckets, Id{0});
      for (Id i = b; i < e; ++i) ++h[(src_k[i] >> shift) & mask];
    });
    // Skip a pass whose digit is the same for every key.
    bool trivial = false;
    for (Id d = 0; d < buckets && !trivial; ++d) {
      Id total = 0;
      for (int c = 0; c < chunks; ++c) total += hist(c)[d];
      if (total == n) trivial = true;
      if (total != 0) break;
    }
    if (trivial) continue;
    // Exclusive offsets, digit-major then chunk order (stability).
    Id running = 0;
    for (Id d = 0; d < buckets; ++d)
      for (int c = 0; c < chunks; ++c) {
        const Id count = hist(c)[d];
        hist(c)[d] = running;
        running += count;
      }
    for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
      Id* pos = hist(c);
      for (Id i = b; i < e; ++i) {
        const Id at = pos[(src_k[i] >> shift) & mask]++;
        dst_k[at] = src_k[i];
        dst_v[at] = src_v[i];
      }
    });
    std::swap(src_k, dst_k);
    std::swap(src_v, dst_v);
  }
  return src_k != keys;
}

template <class K, class V>
void sort_pairs(std::vector<K>& keys, std::vector<V>& values, int significant_bits = int(sizeof(K) * 8)) {
  const Id n = static_cast<Id>(keys.size());
  if (n <= 1 || significant_bits <= 0) return;
  std::vector<K> keys_tmp(n);
  std::vector<V> values_tmp(n);
  if (sort_pairs_passes(keys.data(), values.data(), keys_tmp.data(), values_tmp.data(), n, significant_bits)) {
    keys.swap(keys_tmp);
    values.swap(values_tmp);
  }
}

// The same over n pairs in place at (keys, values) (the device layer's CPU
// device sorts arrays it does not hold as vectors): the scratch is
// allocated here, and the pairs copied back when they end in it.
template <class K, class V>
void sort_pairs(K* keys, V* values, Id n, int significant_bits = int(sizeof(K) * 8)) {
  if (n <= 1 || significant_bits <= 0) return;
  std::vector<K> keys_tmp(n);
  std::vector<V> values_tmp(n);
  if (sort_pairs_passes(keys, values, keys_tmp.data(), values_tmp.data(), n, significant_bits))
    for_each(n, [&](Id i) { keys[i] = keys_tmp[i], values[i] = values_tmp[i]; });
}

}  // namespace keymesh::parallel
