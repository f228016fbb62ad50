#pragma once
// Distributed KEY-REDUCE of point keys: one global id per distinct key over
// all ranks, with no spatial search.
//
// Every rank holds the keys of its points in ascending order; a key may be
// held by several ranks (the points on the plane two slabs share). Keys are
// split into `segments` (an isovalue each) and, within a segment, owned by
// rank by key range in rank order: rank q owns the keys of segment s in
// [first_key(s, q), first_key(s, q + 1)), and first_key(s, P) ends the
// segment (the ranges ascend with s, then q). Each rank numbers the keys it
// owns; the others send the keys they hold but do not own to the owners
// (all-to-all by key range) and get back their global ids (the index map).
// Global ids follow key order within a segment, segment after segment: the
// numbering a single process gives the same keys.
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "keymesh/core/types.hpp"

namespace keymesh::distributed {

struct GlobalNumbering {
  std::vector<std::uint64_t> ids;   // per local key
  std::vector<std::uint8_t> owned;  // per local key: 1 when this rank owns it
  // Keys owned per rank and segment, counts[q * segments + s], on every rank.
  std::vector<long long> counts;
  long long total = 0;              // distinct keys over all ranks
  std::uint64_t keys_requested = 0; // keys this rank asked their owners for
  std::uint64_t bytes_sent = 0;     // by this rank in the exchange
  // First global id of (segment s, rank q).
  long long first_id(int s, int q) const { return first_ids[static_cast<std::size_t>(s) * ranks + q]; }
  int ranks = 1, segments = 1;
  std::vector<long long> first_ids;
};

// The values merged with the keys: `bytes` bytes per local key at `values`
// (this rank's partial results), combined by `merge(acc, part)`: the merge
// operator of keyreduce::reduce (associative and commutative), type-erased
// so that the exchange moves bytes. Build one with value_merge().
struct ValueMerge {
  void* values = nullptr;
  std::size_t bytes = 0;
  std::function<void(void* acc, const void* part)> merge;
};

// Collective over MPI_COMM_WORLD. Throws InputError when a rank asks for a
// key its owner does not hold (the ranks read different inputs).
// Costs O(segments * P * log n) searches plus a pass over the keys not
// owned; the owned ones are numbered in one sweep.
//
// With `values` the fields merge the same way: every copy's partial value
// travels with its key to the owner, which merges them into its own in
// sender rank order (a fixed order), and every copy receives the result;
// the caller applies the transform (e.g. normalising). Deterministic for a
// given P.
GlobalNumbering number_keys(std::span<const std::uint64_t> keys, int segments,
                            const std::function<std::uint64_t(int segment, int rank)>& first_key,
                            const ValueMerge* values = nullptr);

// A ValueMerge over one value of type V per key, e.g.
// value_merge(normal_sums, add) for Vec3f sums.
template <class V, class Merge>
ValueMerge value_merge(std::vector<V>& values, Merge merge) {
  return ValueMerge{values.data(), sizeof(V), [merge](void* acc, const void* part) {
                      V& a = *static_cast<V*>(acc);
                      a = merge(a, *static_cast<const V*>(part));
                    }};
}

}  // namespace keymesh::distributed
