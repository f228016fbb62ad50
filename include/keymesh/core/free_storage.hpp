#pragma once
// Gives a vector's storage back now, when a pass no longer needs it and a
// larger output is about to be allocated. `v = {}` does not do this: it
// resolves to the initializer-list assignment, which clears the elements
// and keeps the capacity (measured: the subdivision's edge keys stayed
// allocated beside its output).
#include <vector>

namespace keymesh {

template <class T, class Allocator>
void free_storage(std::vector<T, Allocator>& v) {
  std::vector<T, Allocator>().swap(v);
}

}  // namespace keymesh
