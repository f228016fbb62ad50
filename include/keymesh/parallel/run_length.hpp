#pragma once
// Run-length encoding of a sorted key array: the distinct keys and, for each,
// the offset of its run. offsets has one more entry than unique_keys; run g
// spans [offsets[g], offsets[g+1]).
#include <vector>

#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh::parallel {

template <class K>
void run_length(const K* sorted, Id n, std::vector<K>& unique_keys, std::vector<Id>& offsets) {
  // heads[i] = 1 where a new run starts; its scan is the run's index.
  std::vector<Id> head_rank(n);
  for_each(n, [&](Id i) { head_rank[i] = (i == 0 || sorted[i] != sorted[i - 1]) ? 1 : 0; });
  const Id groups = exclusive_scan(head_rank.data(), head_rank.data(), n);
  unique_keys.resize(groups);
  offsets.resize(groups + 1);
  for_each(n, [&](Id i) {
    if (i == 0 || sorted[i] != sorted[i - 1]) {
      unique_keys[head_rank[i]] = sorted[i];
      offsets[head_rank[i]] = i;
    }
  });
  offsets[groups] = n;
}

// out[i] = in[index[i]]
template <class T, class I>
void gather(const T* in, const I* index, Id n, T* out) {
  for_each(n, [&](Id i) { out[i] = in[index[i]]; });
}

// out[index[i]] = in[i] (index must be a permutation or injective)
template <class T, class I>
void scatter(const T* in, const I* index, Id n, T* out) {
  for_each(n, [&](Id i) { out[index[i]] = in[i]; });
}

// out[i] = first position in sorted[0, n) whose key is not less than queries[i].
template <class K, class I>
void lower_bound(const K* sorted, Id n, const K* queries, Id q, I* out) {
  for_each(q, [&](Id i) {
    Id lo = 0, hi = n;
    const K k = queries[i];
    while (lo < hi) {
      const Id mid = lo + (hi - lo) / 2;
      if (sorted[mid] < k) lo = mid + 1; else hi = mid;
    }
    out[i] = static_cast<I>(lo);
  });
}

}  // namespace keymesh::parallel
