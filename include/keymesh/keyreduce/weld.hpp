#pragma once
// The weld step every generator shares: its map step emits one key per pair
// (a soup corner, a new point's parent edge, a face centre), and weld()
// turns the pairs into connected points by one of three plans:
//  - Dense:      KEY-REDUCE with direct addressing; keys known to lie in
//                [0, key_range) (implicit ids on a grid);
//  - Sort:       KEY-REDUCE with a radix sort of the key's significant bits
//                (keys with no small known range: edges of unstructured grids);
//  - ByPosition: VERTEX-WELD, the paper's baseline: the pairs' positions,
//                sorted by coordinates; equal coordinates make one point.
// All three return Groups (unique_keys, index_map, and with Order::Build the
// grouped pair order). KEY-REDUCE's groups come in increasing key order;
// VERTEX-WELD's in lexicographic position order, each group's key being that
// of its first pair. Voxel-grid marching cubes numbers its keys without a soup
// (src/generate/contour/contour_rows.hpp) and is not a client.
#include <cstdint>
#include <utility>
#include <vector>

#include "keymesh/core/free_storage.hpp"
#include "keymesh/core/types.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/weld/vertex_weld.hpp"

namespace keymesh::keyreduce {

enum class WeldPlan { Dense, Sort, ByPosition };

template <class K>
struct WeldSpec {
  WeldPlan plan = WeldPlan::Sort;
  K key_range = 0;       // Dense: every key < key_range
  int key_bits = 0;      // Sort: how many low bits of a key may be non-zero
  Order order = Order::Skip;
};

// What weld() may hand back besides the groups.
struct WeldExtras {
  // ByPosition: the welded points' coordinates (3 per group), so the caller
  // need not recompute them.
  Array<float>* points = nullptr;
  // Every group's first pair (smallest pair index): the pair a caller takes
  // a group's values from when pairs of one key may round differently.
  std::vector<std::uint32_t>* first = nullptr;
};

// Every group's first pair (WeldExtras::first) from the index map.
template <class K>
void first_pairs(const Groups<K>& groups, Id n, std::vector<std::uint32_t>& first) {
  first.assign(static_cast<std::size_t>(groups.num_groups()), 0);
  for (Id i = n - 1; i >= 0; --i) first[groups.index_map[i]] = static_cast<std::uint32_t>(i);
}

// `position(i, xyz)` writes pair i's coordinates; called only by ByPosition.
template <class K, class Position>
Groups<K> weld(const K* keys, Id n, const WeldSpec<K>& spec, Position&& position, WeldExtras extras = {}) {
  if (spec.plan == WeldPlan::ByPosition) {
    std::vector<float> xyz(static_cast<std::size_t>(3 * n));
    parallel::for_each(n, [&](Id i) { position(i, &xyz[3 * i]); });
    weld::WeldResult w = weld::vertex_weld(xyz.data(), n);
    free_storage(xyz);
    Groups<K> groups;
    groups.index_map = std::move(w.index_map);
    groups.unique_keys.resize(w.first.size());
    parallel::for_each(groups.num_groups(), [&](Id g) { groups.unique_keys[g] = keys[w.first[g]]; });
    if (spec.order == Order::Build) build_order(groups);
    if (extras.points) *extras.points = std::move(w.points);
    if (extras.first) *extras.first = std::move(w.first);
    return groups;
  }
  Groups<K> groups = spec.plan == WeldPlan::Dense ? partition_dense(keys, n, spec.key_range, spec.order)
                                                  : partition_sort(keys, n, spec.key_bits, spec.order);
  if (extras.first) first_pairs(groups, n, *extras.first);
  return groups;
}

// The same on keys the caller gives up: the sort plan sorts them in their
// own storage (partition_sort on a vector); the other plans read them, and
// `position` may still read the caller's vector, which only the sort plan
// empties.
template <class K, class Position>
Groups<K> weld(std::vector<K>&& keys, const WeldSpec<K>& spec, Position&& position, WeldExtras extras = {}) {
  if (spec.plan != WeldPlan::Sort)
    return weld(keys.data(), static_cast<Id>(keys.size()), spec, std::forward<Position>(position), extras);
  const Id n = static_cast<Id>(keys.size());
  Groups<K> groups = partition_sort(std::move(keys), spec.key_bits, spec.order);
  if (extras.first) first_pairs(groups, n, *extras.first);
  return groups;
}

}  // namespace keymesh::keyreduce
