#pragma once
// Stable LSD radix sort of (key, value) pairs with unsigned 32- or 64-bit
// keys. `significant_bits` says how many low key bits can be non-zero, so a
// key known to fit in 23 bits costs three 8-bit passes, not eight. Passes in
// which every key has the same digit are skipped. Each pass histograms fixed
// contiguous chunks and scatters them in chunk order: the result is the
// stable order, independent of the thread count.
#include <array>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

#include "keymesh/parallel/for_each.hpp"

namespace keymesh::parallel {

// Number of bits needed to represent `max_key` (0 for 0).
template <class K>
int bits_needed(K max_key) {
  int b = 0;
  while (b < int(sizeof(K) * 8) && (max_key >> b) != 0) ++b;
  return b;
}

template <class K, class V>
void sort_pairs(std::vector<K>& keys, std::vector<V>& values, int significant_bits = int(sizeof(K) * 8)) {
  static_assert(std::is_unsigned_v<K>, "radix sort keys are unsigned integers");
  constexpr int kDigitBits = 8;
  constexpr int kBuckets = 1 << kDigitBits;
  const Id n = static_cast<Id>(keys.size());
  if (n <= 1) return;
  if (significant_bits > int(sizeof(K) * 8)) significant_bits = int(sizeof(K) * 8);
  const int passes = (significant_bits + kDigitBits - 1) / kDigitBits;
  if (passes == 0) return;

  std::vector<K> keys_tmp(n);
  std::vector<V> values_tmp(n);
  const int chunks = chunk_count(n, 1 << 15);
  std::vector<std::array<Id, kBuckets>> hist(chunks);

  K* src_k = keys.data();
  V* src_v = values.data();
  K* dst_k = keys_tmp.data();
  V* dst_v = values_tmp.data();
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = pass * kDigitBits;
    for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
      auto& h = hist[c];
      h.fill(0);
      for (Id i = b; i < e; ++i) ++h[(src_k[i] >> shift) & (kBuckets - 1)];
    });
    // Skip a pass whose digit is the same for every key.
    bool trivial = false;
    for (int d = 0; d < kBuckets && !trivial; ++d) {
      Id total = 0;
      for (int c = 0; c < chunks; ++c) total += hist[c][d];
      if (total == n) trivial = true;
      if (total != 0) break;
    }
    if (trivial) continue;
    // Exclusive offsets, digit-major then chunk order (stability).
    Id running = 0;
    for (int d = 0; d < kBuckets; ++d)
      for (int c = 0; c < chunks; ++c) {
        const Id count = hist[c][d];
        hist[c][d] = running;
        running += count;
      }
    for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
      auto& pos = hist[c];
      for (Id i = b; i < e; ++i) {
        const Id at = pos[(src_k[i] >> shift) & (kBuckets - 1)]++;
        dst_k[at] = src_k[i];
        dst_v[at] = src_v[i];
      }
    });
    std::swap(src_k, dst_k);
    std::swap(src_v, dst_v);
  }
  if (src_k != keys.data()) {
    keys.swap(keys_tmp);
    values.swap(values_tmp);
  }
}

}  // namespace keymesh::parallel
