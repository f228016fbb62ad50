#pragma once
// Scratch whose every element a parallel pass writes before any is read
// (the keys of a map step): left unwritten at allocation, so no serial zero
// fill touches its pages before the threads do, and huge pages asked for,
// as parallel::resize_fresh does for outputs.
#include <cstddef>
#include <memory>

#include "keymesh/core/huge_pages.hpp"

namespace keymesh {

template <class T>
std::unique_ptr<T[]> uninitialized_array(std::size_t n) {
  auto a = std::make_unique_for_overwrite<T[]>(n);
  advise_huge_pages(a.get(), n * sizeof(T));
  return a;
}

// Scratch a thread keeps between calls (a session contouring one volume
// after another reuses mapped pages instead of faulting in fresh ones) is
// given back once it holds more than this.
inline constexpr std::size_t kKeepScratchBytes = std::size_t{256} << 20;

// An uninitialized_array kept between calls (a session's scratch): grown to
// the size asked for, never shrunk; its contents are dropped when it grows.
template <class T>
struct KeptArray {
  std::unique_ptr<T[]> elements;
  std::size_t size = 0;

  T* room_for(std::size_t n) {
    if (n > size) elements = uninitialized_array<T>(n), size = n;
    return elements.get();
  }
  T* data() { return elements.get(); }
  const T* data() const { return elements.get(); }
};

}  // namespace keymesh
