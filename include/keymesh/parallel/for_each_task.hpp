#pragma once
// Independent tasks of widely different cost (a segment, a chunk), run with
// dynamic load balancing; a task may throw. An exception cannot leave an
// OpenMP region, so each task's is kept and, after all have run, the first
// by index is rethrown: the same error whatever the thread count. Loops
// inside a task run on its thread (nested regions get one thread), in the
// same fixed chunks as anywhere else, so results do not change.
#include <exception>
#include <vector>

#include "keymesh/parallel/for_each.hpp"

namespace keymesh::parallel {

template <class F>
void for_each_task(Id n, F&& f) {
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(n));
  for_each_dynamic(n, [&](Id i) {
    try {
      f(i);
    } catch (...) {
      errors[static_cast<std::size_t>(i)] = std::current_exception();
    }
  }, 1);
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace keymesh::parallel
