#pragma once
// Large output arrays sized once, with their first touch shared by the
// threads. On the development VMs a first touch (a page fault, the kernel
// zeroing the page) costs more than the writes that follow, and
// std::vector::resize makes it in one thread while it zero-fills. Here the
// kernel is asked for huge pages first (fewer faults), the threads fault the
// pages in parallel with one write per page (the kernel zeroes each page it
// maps, so writing the rest of the page would only repeat that), and only
// then does resize zero-fill memory that is already mapped.
#include <cstddef>
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
    // Raw storage past the elements held: bytes may be written, and resize
    // zero-fills them after.
    auto* raw = reinterpret_cast<volatile unsigned char*>(v.data());
    constexpr std::size_t kPage = 4096;
    const std::size_t first = (v.size() * sizeof(T) + kPage - 1) / kPage;
    const std::size_t pages = (bytes + kPage - 1) / kPage;
    if (pages > first)
      for_each(static_cast<Id>(pages - first), [&](Id p) { raw[(first + static_cast<std::size_t>(p)) * kPage] = 0; },
               512);
  }
  v.resize(n);
}

}  // namespace keymesh::parallel
