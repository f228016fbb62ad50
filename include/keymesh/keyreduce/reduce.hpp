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

}  // namespace keymesh::keyreduce
