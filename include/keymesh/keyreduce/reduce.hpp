#pragma once
// KEY-REDUCE, reduce half (paper, Section 4.1): every group of pairs becomes
// one output value.
//
//   out[g] = transform(merge(...merge(merge(v[p0], v[p1]), v[p2])...), count)
//
// where p0 < p1 < ... are the group's pair indices. `merge` must be
// associative and commutative (so that distributed or streamed reductions can
// combine partial results); the fixed left-to-right order over increasing pair
// indices makes floating-point results bit-identical at any thread count.
#include <utility>

#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::keyreduce {

// value(i) returns the value of pair i (an array lookup or a computation:
// a face normal shared by the three corners of a triangle needs no copies).
template <class K, class ValueOf, class Merge, class Transform, class Out>
void reduce(const Groups<K>& groups, ValueOf&& value, Merge&& merge, Transform&& transform, Out* out) {
  const Id g_count = groups.num_groups();
  const auto* offsets = groups.offsets.data();
  const auto* order = groups.order.data();
  parallel::for_each(g_count, [&](Id g) {
    Id j = offsets[g];
    const Id end = offsets[g + 1];
    auto acc = value(static_cast<Id>(order[j]));
    for (++j; j < end; ++j) acc = merge(acc, value(static_cast<Id>(order[j])));
    out[g] = transform(acc, end - offsets[g]);
  }, 1024);
}

// Convenience: reduce an array of values.
template <class K, class V, class Merge, class Transform, class Out>
void reduce_values(const Groups<K>& groups, const V* values, Merge&& merge, Transform&& transform, Out* out) {
  reduce(groups, [values](Id i) { return values[i]; }, std::forward<Merge>(merge),
         std::forward<Transform>(transform), out);
}

// The reduce half by scattering, for pairs whose groups are local (no pair
// order needed, so no counting sort). The pairs are cut into consecutive
// blocks, block b spanning [block_begin[b], block_begin[b + 1]), such that
// block b shares groups with blocks b - 1 and b + 1 at most. Blocks of one
// parity then never share a group: the even blocks merge into `acc` in
// parallel, then the odd ones. Each group's merge order (its pairs in
// increasing index within a block, the even block before the odd one) is
// fixed by the input alone, so floating-point results are bit-identical at
// any thread count. `acc` holds `groups` values on return, merged from
// `identity` (which must be merge's neutral element: 0 for a sum).
//
// Marching cubes gives such blocks for free: the soup is written voxel slab
// after voxel slab, and an edge's point is shared only by the slabs on
// either side of its plane.
//
// `arity` pairs in a row share one value: pair i's value is value(i / arity)
// (a triangle's three corners share its face normal, computed once). Block
// bounds must be multiples of `arity`.
template <class Index, class ValueOf, class Merge, class Acc>
void reduce_blocked(const Index* index_map, const Id* block_begin, Id blocks, int arity, ValueOf&& value,
                    Merge&& merge, Acc identity, Acc* acc, Id groups) {
  parallel::for_each(groups, [&](Id g) { acc[g] = identity; });
  for (Id parity = 0; parity < 2; ++parity) {
    parallel::for_each_dynamic((blocks + 1 - parity) / 2, [&](Id h) {
      const Id b = 2 * h + parity;
      for (Id item = block_begin[b] / arity; item < block_begin[b + 1] / arity; ++item) {
        const auto v = value(item);
        for (Id i = item * arity; i < (item + 1) * arity; ++i) {
          Acc& a = acc[static_cast<Id>(index_map[i])];
          a = merge(a, v);
        }
      }
    }, 1);
  }
}

}  // namespace keymesh::keyreduce
