#pragma once
// Exclusive prefix sum: out[i] = in[0] + ... + in[i-1]; returns the total.
// `out` may alias `in`. Two passes over fixed chunks: deterministic.
#include <vector>

#include "keymesh/parallel/for_each.hpp"

namespace keymesh::parallel {

template <class T, class U>
U exclusive_scan(const T* in, U* out, Id n) {
  const int chunks = chunk_count(n, 1 << 16);
  if (chunks <= 1) {
    U sum{};
    for (Id i = 0; i < n; ++i) {
      const U v = static_cast<U>(in[i]);
      out[i] = sum;
      sum += v;
    }
    return sum;
  }
  std::vector<U> partial(chunks + 1, U{});
  for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
    U s{};
    for (Id i = b; i < e; ++i) s += static_cast<U>(in[i]);
    partial[c + 1] = s;
  });
  for (int c = 0; c < chunks; ++c) partial[c + 1] += partial[c];
  for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
    U sum = partial[c];
    for (Id i = b; i < e; ++i) {
      const U v = static_cast<U>(in[i]);
      out[i] = sum;
      sum += v;
    }
  });
  return partial[chunks];
}

template <class T>
T exclusive_scan(std::vector<T>& values) {
  return exclusive_scan(values.data(), values.data(), static_cast<Id>(values.size()));
}

}  // namespace keymesh::parallel
