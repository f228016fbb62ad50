#pragma once
// The parallel loop every algorithm is written with. Functors take indices
// and must not allocate, so the same functor can later run on a GPU.
#include <algorithm>

#include "keymesh/core/types.hpp"
#include "keymesh/parallel/threads.hpp"

namespace keymesh::parallel {

// Number of contiguous chunks a range of n is split into: thread_count(),
// but never more than needed for ranges too small to be worth splitting.
inline int chunk_count(Id n, Id min_per_chunk = 4096) {
  const Id by_size = std::max<Id>(1, n / std::max<Id>(1, min_per_chunk));
  return static_cast<int>(std::min<Id>(thread_count(), by_size));
}

// Bounds of chunk c of `chunks` over [0, n): fixed by (n, chunks) only.
inline Id chunk_begin(Id n, int chunks, int c) { return n * c / chunks; }

// Calls f(begin, end, c) for every chunk c in [0, chunks), in parallel.
template <class F>
void for_each_chunk(Id n, int chunks, F&& f) {
  if (chunks <= 1) {
    f(Id{0}, n, 0);
    return;
  }
#pragma omp parallel for schedule(static, 1) num_threads(chunks)
  for (int c = 0; c < chunks; ++c) f(chunk_begin(n, chunks, c), chunk_begin(n, chunks, c + 1), c);
}

// Calls f(i) for every i in [0, n), in parallel.
template <class F>
void for_each(Id n, F&& f, Id min_per_chunk = 4096) {
  const int chunks = chunk_count(n, min_per_chunk);
  for_each_chunk(n, chunks, [&](Id b, Id e, int) {
    for (Id i = b; i < e; ++i) f(i);
  });
}

// Calls f(i) for i in [0, n) with dynamic load balancing, for loops whose
// iterations differ widely in cost. Only for work whose result does not
// depend on which thread runs which i (each i writes its own outputs).
template <class F>
void for_each_dynamic(Id n, F&& f, Id grain = 16) {
  const int threads = thread_count();
  if (threads <= 1 || n <= grain) {
    for (Id i = 0; i < n; ++i) f(i);
    return;
  }
#pragma omp parallel for schedule(dynamic, grain) num_threads(threads)
  for (Id i = 0; i < n; ++i) f(i);
}

}  // namespace keymesh::parallel
