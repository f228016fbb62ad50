#pragma once
// for_each_task (for_each_task.hpp) with one more piece of work, `beside`,
// run on the calling thread while the other threads take the tasks; the
// calling thread then takes tasks too. For serial work that must stay on the
// calling thread (it writes files into the thread's OutputTransaction) and
// need not wait for the tasks: it overlaps them instead of running before or
// after them while the other threads wait. Each task's exception is kept and
// the first by index rethrown, then beside's: the same error whatever the
// thread count and the order in which things finished.
#include <omp.h>

#include <exception>
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/parallel/threads.hpp"

namespace keymesh::parallel {

template <class F, class G>
void for_each_task_beside(Id n, F&& f, G&& beside) {
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(n));
  std::exception_ptr beside_error;
  auto task = [&](Id i) {
    try {
      f(i);
    } catch (...) {
      errors[static_cast<std::size_t>(i)] = std::current_exception();
    }
  };
  auto run_beside = [&] {
    try {
      beside();
    } catch (...) {
      beside_error = std::current_exception();
    }
  };
  if (thread_count() <= 1) {
    run_beside();
    for (Id i = 0; i < n; ++i) task(i);
  } else {
#pragma omp parallel num_threads(thread_count())
    {
      // Thread 0 is the calling thread (a nested call gets a team of one).
      if (omp_get_thread_num() == 0) run_beside();
#pragma omp for schedule(dynamic, 1) nowait
      for (Id i = 0; i < n; ++i) task(i);
    }
  }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  if (beside_error) std::rethrow_exception(beside_error);
}

}  // namespace keymesh::parallel
