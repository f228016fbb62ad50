// parallel::for_each_task_pipeline and parallel::for_each_task_beside: every
// task runs once, a second-stage task only after its first-stage task, the
// errors in stage order then index order whatever the thread count, and
// beside's work on the calling thread.
#include <gtest/gtest.h>

#include <atomic>
#include <functional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "keymesh/parallel/for_each_task_beside.hpp"
#include "keymesh/parallel/task_pipeline.hpp"
#include "thread_count_test.hpp"

namespace kp = keymesh::parallel;
using keymesh::Id;

namespace {

class TaskPipelineThreads : public keymesh::tests::ThreadCountTest {};

std::string error_of(const std::function<void()>& run) {
  try {
    run();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no exception";
}

}  // namespace

TEST_P(TaskPipelineThreads, RunsEverySecondTaskOnceAfterItsFirst) {
  constexpr Id n = 60;
  std::vector<std::atomic<int>> firsts(n);
  std::vector<std::vector<int>> seconds(n);
  std::atomic<int> out_of_order{0};
  kp::for_each_task_pipeline(
      n,
      [&](Id i) -> Id {
        seconds[static_cast<std::size_t>(i)].assign(static_cast<std::size_t>(i % 7), 0);
        ++firsts[static_cast<std::size_t>(i)];
        return i % 7;  // some open none
      },
      [&](Id i, Id j) {
        if (firsts[static_cast<std::size_t>(i)].load() != 1) ++out_of_order;
        ++seconds[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
      });
  EXPECT_EQ(out_of_order.load(), 0);
  for (Id i = 0; i < n; ++i) {
    EXPECT_EQ(firsts[static_cast<std::size_t>(i)].load(), 1);
    EXPECT_EQ(seconds[static_cast<std::size_t>(i)], std::vector<int>(static_cast<std::size_t>(i % 7), 1)) << i;
  }
}

TEST_P(TaskPipelineThreads, FirstStageErrorsComeFirstThenTheLowestSecondStageOne) {
  // Task 3's second stage fails, and so does task 40's first: the first
  // stage's error is the one thrown, and task 40 opens no second stage.
  std::atomic<int> of_failed_first{0};
  EXPECT_EQ(error_of([&] {
              kp::for_each_task_pipeline(
                  50,
                  [&](Id i) -> Id {
                    if (i == 40 || i == 45) throw std::runtime_error("first " + std::to_string(i));
                    return 3;
                  },
                  [&](Id i, Id j) {
                    if (i == 40 || i == 45) ++of_failed_first;
                    if (i == 3 && j == 1) throw std::runtime_error("second 3 1");
                  });
            }),
            "first 40");
  EXPECT_EQ(of_failed_first.load(), 0);
  EXPECT_EQ(error_of([&] {
              kp::for_each_task_pipeline(
                  50, [&](Id) -> Id { return 4; },
                  [&](Id i, Id j) {
                    if ((i == 3 && j == 2) || (i == 3 && j == 3) || (i == 30 && j == 0))
                      throw std::runtime_error("second " + std::to_string(i) + " " + std::to_string(j));
                  });
            }),
            "second 3 2");
}

TEST_P(TaskPipelineThreads, BesideRunsOnTheCallingThreadAndItsErrorComesLast) {
  const std::thread::id caller = std::this_thread::get_id();
  std::thread::id beside_thread;
  std::vector<std::atomic<int>> runs(300);
  kp::for_each_task_beside(
      300, [&](Id i) { ++runs[static_cast<std::size_t>(i)]; }, [&] { beside_thread = std::this_thread::get_id(); });
  EXPECT_EQ(beside_thread, caller);
  for (const auto& r : runs) EXPECT_EQ(r.load(), 1);
  EXPECT_EQ(error_of([&] {
              kp::for_each_task_beside(
                  300,
                  [&](Id i) {
                    if (i == 250 || i == 260) throw std::runtime_error("task " + std::to_string(i));
                  },
                  [&] { throw std::runtime_error("beside"); });
            }),
            "task 250");
  EXPECT_EQ(error_of([&] { kp::for_each_task_beside(300, [](Id) {}, [&] { throw std::runtime_error("beside"); }); }),
            "beside");
}

INSTANTIATE_TEST_SUITE_P(Threads, TaskPipelineThreads, ::testing::Values(1, 2, 3));
