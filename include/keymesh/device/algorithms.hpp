#pragma once
// The device layer: the parallel primitives every generator's device path is
// written with, whatever device runs them (Viskores' device adapter is the
// model: an algorithm never names a backend).
//
// A device (CpuDevice in cpu_device.hpp; CudaDevice in cuda_device.cuh, nvcc
// only) provides:
//   Array<T>                   its memory: data(), size(), movable
//   allocate<T>(n), upload(host, n), download(data, n, host), to_host(array),
//   read(element)              memory between host and device
//   allocate_output<T>(n)      an array a generator hands to its caller (the
//                              CUDA device may take it from other memory)
//   for_each(n, f)             f(i) for i in [0, n): the one parallel loop
//   exclusive_scan(in, out, n) prefix sums in the output's type; returns the total
//   sort_pairs(k, v, n, bits)  stable radix sort of (key, value) pairs in place
//   synchronize()
//   begin_stage(&seconds) -> mark, end_stage(mark)
//                              a named stage's time added to `seconds` (the
//                              CPU's clock; CUDA events on the GPU, read once
//                              the stream is done)
// Everything below is generic, built on those with functors (plain structs
// whose operator() is KEYMESH_HD, so nvcc compiles them for the GPU): a
// device overrides nothing yet. Every primitive's result depends only on
// its input (no atomics, fixed summation orders), so the CPU and the GPU
// give the same bits.
#include <cstdint>

#include "keymesh/core/device.hpp"
#include "keymesh/core/types.hpp"

namespace keymesh::device {

namespace functors {

template <class T>
struct Fill {
  T* out;
  T value;
  KEYMESH_HD void operator()(Id i) const { out[i] = value; }
};

template <class T>
struct Copy {
  const T* in;
  T* out;
  KEYMESH_HD void operator()(Id i) const { out[i] = in[i]; }
};

template <class T>
struct Iota {
  T* out;
  KEYMESH_HD void operator()(Id i) const { out[i] = static_cast<T>(i); }
};

template <class T, class I>
struct Gather {
  const T* in;
  const I* index;
  T* out;
  KEYMESH_HD void operator()(Id i) const { out[i] = in[index[i]]; }
};

template <class T, class I>
struct Scatter {
  const T* in;
  const I* index;
  T* out;
  KEYMESH_HD void operator()(Id i) const { out[index[i]] = in[i]; }
};

// 1 where a run of equal sorted keys starts.
template <class K>
struct RunHeads {
  const K* sorted;
  Id* heads;
  KEYMESH_HD void operator()(Id i) const { heads[i] = (i == 0 || sorted[i] != sorted[i - 1]) ? 1 : 0; }
};

// From the exclusive scan of the heads: each run's key and first position,
// and (when asked for) each position's run.
template <class K>
struct RunWrite {
  const K* sorted;
  const Id* head_rank;  // exclusive scan of RunHeads
  K* unique_keys;
  Id* offsets;
  Id* run_of;  // may be null
  KEYMESH_HD void operator()(Id i) const {
    const bool head = i == 0 || sorted[i] != sorted[i - 1];
    const Id run = head ? head_rank[i] : head_rank[i] - 1;
    if (head) {
      unique_keys[run] = sorted[i];
      offsets[run] = i;
    }
    if (run_of) run_of[i] = run;
  }
};

template <class T>
struct SetOne {
  T* at;
  T value;
  KEYMESH_HD void operator()(Id) const { *at = value; }
};

template <class ValueOf, class Op, class Acc>
struct SegmentReduce {
  const Id* offsets;
  ValueOf value;
  Op op;
  Acc* acc;
  KEYMESH_HD void operator()(Id s) const {
    Acc a = acc[s];
    for (Id j = offsets[s]; j < offsets[s + 1]; ++j) a = op(a, value(j));
    acc[s] = a;
  }
};

}  // namespace functors

template <class D, class T>
void fill(const D& d, T* out, Id n, T value) {
  d.for_each(n, functors::Fill<T>{out, value});
}

// out[i] = in[i] (no overlap)
template <class D, class T>
void copy(const D& d, const T* in, Id n, T* out) {
  d.for_each(n, functors::Copy<T>{in, out});
}

// out[i] = i
template <class D, class T>
void iota(const D& d, T* out, Id n) {
  d.for_each(n, functors::Iota<T>{out});
}

// out[i] = in[index[i]]
template <class D, class T, class I>
void gather(const D& d, const T* in, const I* index, Id n, T* out) {
  d.for_each(n, functors::Gather<T, I>{in, index, out});
}

// out[index[i]] = in[i] (index injective)
template <class D, class T, class I>
void scatter(const D& d, const T* in, const I* index, Id n, T* out) {
  d.for_each(n, functors::Scatter<T, I>{in, index, out});
}

// Host data where the device can read it: on a device whose memory is the
// host's, `host` itself (no copy); otherwise a copy uploaded into `holder`.
template <class D, class T>
const T* readable(const D& d, const T* host, Id n, typename D::template Array<T>& holder) {
  if constexpr (D::kHostMemory) {
    return host;
  } else {
    holder = d.upload(host, n);
    return holder.data();
  }
}

// The runs of a sorted key array: the distinct keys, in order, and the
// offsets of their runs (one more than the runs: run g spans
// [offsets[g], offsets[g + 1])).
template <class D, class K>
struct Runs {
  typename D::template Array<K> unique_keys;
  typename D::template Array<Id> offsets;
  Id count = 0;
};

// Run-length encoding of n sorted keys; run_of, when given (n entries),
// receives each position's run.
template <class D, class K>
Runs<D, K> run_length(const D& d, const K* sorted, Id n, Id* run_of = nullptr) {
  Runs<D, K> r;
  auto heads = d.template allocate<Id>(n);
  d.for_each(n, functors::RunHeads<K>{sorted, heads.data()});
  r.count = d.exclusive_scan(heads.data(), heads.data(), n);
  r.unique_keys = d.template allocate<K>(r.count);
  r.offsets = d.template allocate<Id>(r.count + 1);
  d.for_each(n, functors::RunWrite<K>{sorted, heads.data(), r.unique_keys.data(), r.offsets.data(), run_of});
  d.for_each(1, functors::SetOne<Id>{r.offsets.data() + r.count, n});
  return r;
}

// Segmented reduce in a fixed order: for every segment s, acc[s] (its
// initial value on entry) becomes op(...op(op(acc[s], value(b)), value(b + 1))..., value(e - 1))
// over [b, e) = [offsets[s], offsets[s + 1]). One thread per segment, left to
// right: the order a floating-point sum needs to give the same bits on every
// device (a tree reduction, CUB's, would not).
template <class D, class ValueOf, class Op, class Acc>
void segmented_reduce(const D& d, const Id* offsets, Id segments, const ValueOf& value, const Op& op, Acc* acc) {
  d.for_each(segments, functors::SegmentReduce<ValueOf, Op, Acc>{offsets, value, op, acc});
}

}  // namespace keymesh::device
