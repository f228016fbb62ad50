#pragma once
// KEY-REDUCE, partition half (paper, Section 4.1): group n keyed pairs by key.
//
//   keys:         [ 7  3  7  9  3  7 ]        pair i has key keys[i]
//   unique_keys:  [ 3  7  9 ]                 one group per distinct key, increasing
//   index_map:    [ 1  0  1  2  0  1 ]        the group of every pair (rewrites cell lists)
//   offsets:      [ 0  2  5  6 ]              group g owns order[offsets[g] .. offsets[g+1])
//   order:        [ 1  4  0  2  5  3 ]        pair indices grouped by key, increasing within a group
//
// The grouping is built once and reused for every field reduced over it (like
// Viskores' Keys). Two partition plans give identical Groups:
//  - sort:  stable radix sort of (key, pair) with only the significant key bits;
//  - dense: direct addressing for keys known to lie in [0, key_range): a bitmap
//           of present keys, a prefix count of its words, and a rank within a
//           word; no sort at all (implicit edge ids on a voxel grid).
// Both are deterministic: the result depends only on the keys.
#include <cstdint>
#include <vector>

#include "keymesh/core/array.hpp"
#include "keymesh/core/types.hpp"

namespace keymesh::keyreduce {

enum class Plan { Sort, Dense };

// Whether the group offsets and the grouped pair order are built. A weld
// without attribute merging needs only unique_keys and index_map.
enum class Order { Skip, Build };

template <class K>
struct Groups {
  std::vector<K> unique_keys;
  Array<std::uint32_t> index_map;        // an output array (a mesh's connectivity)
  std::vector<Id> offsets;              // empty when built with Order::Skip
  std::vector<std::uint32_t> order;     // empty when built with Order::Skip

  Id num_groups() const { return static_cast<Id>(unique_keys.size()); }
  Id num_pairs() const { return static_cast<Id>(index_map.size()); }
  bool has_order() const { return !offsets.empty(); }
  Id count(Id g) const { return offsets[g + 1] - offsets[g]; }
};

// Sort plan. `significant_bits`: how many low bits of a key may be non-zero.
// Throws LimitError when n does not fit the 32-bit index map.
template <class K>
Groups<K> partition_sort(const K* keys, Id n, int significant_bits, Order order = Order::Build);

// The same on keys the caller gives up: sorted in their own storage, so no
// copy of them is held beside the sort's buffers (8 bytes a pair less at
// the weld's peak with 64-bit keys).
template <class K>
Groups<K> partition_sort(std::vector<K>&& keys, int significant_bits, Order order = Order::Build);

// Merge plan, for keys that come as a few increasing runs (the point keys
// of several welded pieces, each in key order): the runs merged pairwise,
// stably, with no radix passes; a single run (keys already in order) costs
// one scan. Any keys are accepted (n keys in r runs: O(n log r)). The same
// Groups as partition_sort. Serial: meant for one piece's weld inside a task.
template <class K>
Groups<K> partition_runs(const K* keys, Id n, Order order = Order::Build);

// Dense plan: every key must be < key_range (checked; InputError otherwise).
template <class K>
Groups<K> partition_dense(const K* keys, Id n, K key_range, Order order = Order::Build);

// Builds offsets and order for Groups made with Order::Skip.
template <class K>
void build_order(Groups<K>& groups);

}  // namespace keymesh::keyreduce
