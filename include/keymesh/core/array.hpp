#pragma once
// Array<T>: the std::vector that mesh outputs are stored in (SurfaceMesh's
// points, connectivity and offsets, every Field's values, UnstructuredGrid's
// points, a weld's index map). The one difference from std::vector<T>: elements a size
// constructor or resize(n) adds are default-initialised, i.e. left unwritten
// for the arithmetic types stored here, as vtkDataArray::SetNumberOfValues
// and numpy.empty leave them. A generator sizes its output once and writes
// every element in place; std::vector's value-initialisation would first
// zero-fill it in one thread (a memset of the whole output, 66 MB for a
// 3.7 M-triangle contour) that the writes then repeat. resize(n, 0) and
// assign(n, 0) still fill where zeros are meant. Built with
// -DKEYMESH_POISON_UNWRITTEN, unwritten elements are set to all ones bits
// instead, to catch a reader of elements nobody wrote. Storage of 4 MiB or
// more comes from core/retained_blocks.hpp: a freed output's pages are kept
// mapped for the next one, not faulted in afresh.
#include <cstring>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include "keymesh/core/retained_blocks.hpp"

namespace keymesh {

// std::allocator, but construct(p) with no value default-initialises
// (`new (p) T`, no zeros) where std::allocator value-initialises.
template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  using value_type = T;
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() noexcept = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    if (retained_blocks::kInUse && n >= retained_blocks::kMinBytes / sizeof(T)) {
      if (n > std::allocator_traits<std::allocator<T>>::max_size(*this)) throw std::bad_array_new_length();
      return static_cast<T*>(retained_blocks::acquire(n * sizeof(T)));
    }
    return std::allocator<T>::allocate(n);
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (retained_blocks::kInUse && n >= retained_blocks::kMinBytes / sizeof(T))
      retained_blocks::release(p, n * sizeof(T));
    else
      std::allocator<T>::deallocate(p, n);
  }

  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
#ifdef KEYMESH_POISON_UNWRITTEN
    // Debug builds: unwritten elements get all bits set (NaN floats, ids
    // past any mesh), so code that wrongly counts on zeros fails its tests
    // instead of passing on the zeros fresh pages happen to hold.
    std::memset(static_cast<void*>(p), 0xff, sizeof(U));
#endif
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <class T, class U>
bool operator==(const DefaultInitAllocator<T>&, const DefaultInitAllocator<U>&) noexcept {
  return true;
}

template <class T>
using Array = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace keymesh
