#pragma once
// Large output arrays sized once, with their first touch shared by the
// threads. On the development VMs a first touch (a page fault, the kernel
// zeroing the page) costs more than the writes that follow, and
// std::vector::resize makes it in one thread while it zero-fills. Here the
// kernel is asked for huge pages first (fewer faults) and the threads fault
// the pages in parallel with one write per page (the kernel zeroes each page
// it maps, so writing the rest of the page would only repeat that). An
// output Array (core/array.hpp) is then sized without a fill: its elements
// are written once, by the generator.
#include <cstddef>
#include <vector>

#include "keymesh/core/huge_pages.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::parallel {

// The pages of fresh storage [data, data + bytes) from byte `from` on,
// faulted in by the threads, one write per page (bytes whose values nobody
// reads yet).
inline void touch_pages(void* data, std::size_t bytes, std::size_t from = 0) {
  auto* raw = static_cast<volatile unsigned char*>(data);
  constexpr std::size_t kPage = 4096;
  const std::size_t first = (from + kPage - 1) / kPage;
  const std::size_t pages = (bytes + kPage - 1) / kPage;
  if (pages > first)
    for_each(static_cast<Id>(pages - first), [&](Id p) { raw[(first + static_cast<std::size_t>(p)) * kPage] = 0; },
             512);
}

// touch_pages, with huge pages asked for first.
inline void fault_in(void* data, std::size_t bytes, std::size_t from = 0) {
  advise_huge_pages(data, bytes);
  touch_pages(data, bytes, from);
}

// Gives `v` room for n elements, its pages faulted in by the threads (no
// element added).
template <class T, class A>
void reserve_fresh(std::vector<T, A>& v, std::size_t n) {
  if (n <= v.capacity()) return;
  v.reserve(n);
  // Raw storage past the elements held: bytes may be written (a resize
  // sets them after).
  fault_in(v.data(), n * sizeof(T), v.size() * sizeof(T));
}

// Sizes `v` to n elements, its new pages faulted in by the threads. The new
// elements are those v.resize(n) makes: unwritten in an Array (the output
// arrays, which their generator writes), zeros in a std::vector.
template <class T, class A>
void resize_fresh(std::vector<T, A>& v, std::size_t n) {
  reserve_fresh(v, n);
  v.resize(n);
}

}  // namespace keymesh::parallel
