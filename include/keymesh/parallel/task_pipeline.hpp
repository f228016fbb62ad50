#pragma once
// Tasks in two stages without a barrier between them: first(i) for every i
// in [0, n) returns how many second-stage tasks it opens, and second(i, j)
// for j in [0, that count) may start as soon as first(i) has ended, while
// other first-stage tasks still run. Threads take a first-stage task while
// any is left, else an open second-stage one (in the order they were
// opened), else wait for one to open. Each task writes its own outputs, so
// results do not depend on the thread count or the order things finish.
// A task's exception is kept (a failed first(i) opens nothing) and, after
// all have run, the first first-stage one by i is rethrown, else the first
// second-stage one by (i, j): the same error whatever the thread count.
// Loops inside a task run on its thread (a nested region gets one thread).
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <utility>
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/parallel/threads.hpp"

namespace keymesh::parallel {

template <class First, class Second>
void for_each_task_pipeline(Id n, First&& first, Second&& second) {
  std::vector<std::exception_ptr> first_errors(static_cast<std::size_t>(n));
  std::vector<std::vector<std::exception_ptr>> second_errors(static_cast<std::size_t>(n));
  std::mutex m;
  std::condition_variable opened;
  std::deque<std::pair<Id, Id>> open;  // second-stage tasks ready to run
  Id next = 0, running_first = 0;
  auto run_first = [&](Id i) {
    Id count = 0;
    try {
      count = first(i);
    } catch (...) {
      first_errors[static_cast<std::size_t>(i)] = std::current_exception();
    }
    second_errors[static_cast<std::size_t>(i)].resize(static_cast<std::size_t>(count));
    return count;
  };
  auto run_second = [&](Id i, Id j) {
    try {
      second(i, j);
    } catch (...) {
      second_errors[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] = std::current_exception();
    }
  };
  auto worker = [&] {
    std::unique_lock<std::mutex> lock(m);
    for (;;) {
      if (next < n) {
        const Id i = next++;
        ++running_first;
        lock.unlock();
        const Id count = run_first(i);
        lock.lock();
        --running_first;
        for (Id j = 0; j < count; ++j) open.emplace_back(i, j);
        opened.notify_all();
      } else if (!open.empty()) {
        const auto [i, j] = open.front();
        open.pop_front();
        lock.unlock();
        run_second(i, j);
        lock.lock();
      } else if (running_first == 0) {
        return;  // nothing open and nothing left to open it
      } else {
        opened.wait(lock);
      }
    }
  };
  if (thread_count() <= 1) {
    worker();
  } else {
#pragma omp parallel num_threads(thread_count())
    worker();
  }
  for (const std::exception_ptr& e : first_errors)
    if (e) std::rethrow_exception(e);
  for (const auto& errors : second_errors)
    for (const std::exception_ptr& e : errors)
      if (e) std::rethrow_exception(e);
}

}  // namespace keymesh::parallel
