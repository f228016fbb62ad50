#pragma once
// Large output arrays sized once, with their first touch shared by the
// threads. On the development VMs a first touch (a page fault, the kernel
// zeroing the page) costs more than the writes that follow, and
// std::vector::resize makes it in one thread while it zero-fills. Here the
// kernel is asked for huge pages first (fewer faults), the threads fault the
// pages in parallel, and only then does resize zero-fill memory that is
// already mapped.
#include <algorithm>
#include <cstddef>
#include <cstring>
#include <vector>

#include "keymesh/core/huge_pages.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::parallel {

// Sizes `v` to n elements (zero-filled, as resize does).
template <class T>
void resize_fresh(std::vector<T>& v, std::size_t n) {
  if (n > v.capacity()) {
    v.reserve(n);
    const std::size_t bytes = n * sizeof(T);
    advise_huge_pages(v.data(), bytes);
    // Raw storage not yet holding elements: bytes may be written.
    auto* raw = reinterpret_cast<unsigned char*>(v.data());
    constexpr std::size_t kChunk = std::size_t{1} << 21;
    for_each(static_cast<Id>((bytes + kChunk - 1) / kChunk), [&](Id c) {
      const std::size_t b = static_cast<std::size_t>(c) * kChunk;
      std::memset(raw + b, 0, std::min(kChunk, bytes - b));
    }, 1);
  }
  v.resize(n);
}

}  // namespace keymesh::parallel
