#pragma once
// Large output arrays sized once, with their first touch shared by the
// threads. On the development VMs a first touch (a page fault, the kernel
// zeroing the page) costs more than the writes that follow, and
// std::vector::resize makes it in one thread while it zero-fills. Here the
// kernel is asked for huge pages first (fewer faults), the threads fault the
// pages in parallel with one write per page (the kernel zeroes each page it
// maps, so writing the rest of the page would only repeat that), and only
// then does resize zero-fill memory that is already mapped.
#include <algorithm>
#include <cstddef>
#include <functional>
#include <memory>
#include <type_traits>
#include <vector>

#include "keymesh/core/huge_pages.hpp"
#include "keymesh/core/uninitialized_array.hpp"
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
// element added: the resize that follows only zero-fills mapped memory).
template <class T>
void reserve_fresh(std::vector<T>& v, std::size_t n) {
  if (n <= v.capacity()) return;
  v.reserve(n);
  // Raw storage past the elements held: bytes may be written, and resize
  // zero-fills them after.
  fault_in(v.data(), n * sizeof(T), v.size() * sizeof(T));
}

// An array of n elements left uninitialised (no zero-fill), its pages
// faulted in by the threads: for output written in place, element by
// element, before anyone reads it.
template <class T>
std::unique_ptr<T[]> fresh_array(std::size_t n) {
  static_assert(std::is_trivially_default_constructible_v<T>);
  std::unique_ptr<T[]> a = uninitialized_array<T>(n);  // huge pages asked for
  touch_pages(a.get(), n * sizeof(T));
  return a;
}

// Sizes `v` to n elements (zero-filled, as resize does).
template <class T>
void resize_fresh(std::vector<T>& v, std::size_t n) {
  reserve_fresh(v, n);
  v.resize(n);
}

// Several arrays sized together: each gets its room (reserve_fresh) when
// added, and run() then sizes them all, one array per thread, the largest
// first. std::vector's resize zero-fills its new elements in one thread,
// at memory speed (66 MB for a 3.7 M-triangle contour); one after the other
// those fills add up, side by side they cost the largest one.
class FreshArrays {
 public:
  // Room for n elements of v now (its data() stays valid: run() does not
  // reallocate); the elements after run().
  template <class T>
  T* add(std::vector<T>& v, std::size_t n) {
    reserve_fresh(v, n);
    jobs_.push_back(Job{n * sizeof(T), [&v, n] { v.resize(n); }});
    return v.data();
  }

  void run() {
    std::sort(jobs_.begin(), jobs_.end(), [](const Job& a, const Job& b) { return a.bytes > b.bytes; });
    for_each_dynamic(static_cast<Id>(jobs_.size()), [&](Id j) { jobs_[static_cast<std::size_t>(j)].resize(); }, 1);
    jobs_.clear();
  }

 private:
  struct Job {
    std::size_t bytes;
    std::function<void()> resize;
  };
  std::vector<Job> jobs_;
};

}  // namespace keymesh::parallel
