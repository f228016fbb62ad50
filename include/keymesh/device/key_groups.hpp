#pragma once
// KEY-REDUCE's partition on a device (the sort plan): n (key, pair) pairs
// grouped by key once, then any number of fields reduced over the groups
// (Viskores' worklet::Keys is the model: partition once, reduce many).
//
// The groups come in increasing key order, a group's pairs in increasing
// pair order (the sort is stable): the order keyreduce::weld's sort plan
// gives on the CPU, so a generator's points and triangles come out the same.
#include <cstdint>
#include <utility>

#include "keymesh/core/device.hpp"
#include "keymesh/core/types.hpp"
#include "keymesh/device/algorithms.hpp"

namespace keymesh::device {

template <class D, class K>
struct KeyGroups {
  typename D::template Array<K> unique_keys;         // per group, increasing
  typename D::template Array<Id> offsets;            // groups + 1: group g's sorted positions
  typename D::template Array<std::uint32_t> sorted_pairs;  // per sorted position: its pair
  typename D::template Array<std::uint32_t> index_map;     // per pair: its group
  Id groups = 0;
};

namespace functors {

// index_map[sorted_pairs[j]] = run_of[j]
struct IndexMap {
  const std::uint32_t* sorted_pairs;
  const Id* run_of;
  std::uint32_t* index_map;
  KEYMESH_HD void operator()(Id j) const { index_map[sorted_pairs[j]] = static_cast<std::uint32_t>(run_of[j]); }
};

}  // namespace functors

// Groups the n keys (sorted in place: `keys` holds them sorted afterwards)
// whose non-zero bits are the low `key_bits` ones. n must fit the 32-bit
// pair indices (a mesh's corner ids): callers check their limits first.
template <class D, class K>
KeyGroups<D, K> group_keys(const D& d, K* keys, Id n, int key_bits) {
  KeyGroups<D, K> g;
  g.sorted_pairs = d.template allocate<std::uint32_t>(n);
  iota(d, g.sorted_pairs.data(), n);
  d.sort_pairs(keys, g.sorted_pairs.data(), n, key_bits);
  auto run_of = d.template allocate<Id>(n);
  Runs<D, K> runs = run_length(d, keys, n, run_of.data());
  g.unique_keys = std::move(runs.unique_keys);
  g.offsets = std::move(runs.offsets);
  g.groups = runs.count;
  g.index_map = d.template allocate_output<std::uint32_t>(n);  // a generator's triangle list
  d.for_each(n, functors::IndexMap{g.sorted_pairs.data(), run_of.data(), g.index_map.data()});
  return g;
}

}  // namespace keymesh::device
