// parallel::for_each_task: every task runs once, the lowest-numbered task's
// exception reaches the caller whatever the thread count, and a parallel
// loop inside a task gives the same result as outside one.
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include "keymesh/parallel/for_each_task.hpp"
#include "thread_count_test.hpp"

namespace kp = keymesh::parallel;
using keymesh::Id;

namespace {

class ForEachTaskThreads : public keymesh::tests::ThreadCountTest {};

}  // namespace

TEST_P(ForEachTaskThreads, RunsEveryTaskOnce) {
  std::vector<std::atomic<int>> runs(1000);
  kp::for_each_task(1000, [&](Id i) { ++runs[static_cast<std::size_t>(i)]; });
  for (const auto& r : runs) EXPECT_EQ(r.load(), 1);
}

TEST_P(ForEachTaskThreads, RethrowsTheFirstTasksError) {
  std::atomic<int> finished{0};
  try {
    kp::for_each_task(200, [&](Id i) {
      if (i % 50 == 17) throw std::runtime_error("task " + std::to_string(i));
      ++finished;
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "task 17");
  }
  EXPECT_EQ(finished.load(), 196);  // the other tasks still ran
}

TEST_P(ForEachTaskThreads, NestedLoopsGiveTheSameResult) {
  // A chunked sum inside each task: the chunks are fixed by (n, thread
  // count), so the per-chunk partial sums match the ones made outside.
  auto chunked = [](Id n) {
    const int chunks = kp::chunk_count(n, 16);
    std::vector<double> part(static_cast<std::size_t>(chunks), 0.0);
    kp::for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
      for (Id i = b; i < e; ++i) part[static_cast<std::size_t>(c)] += 1.0 / static_cast<double>(i + 1);
    });
    return part;
  };
  std::vector<std::vector<double>> inside(8);
  kp::for_each_task(8, [&](Id t) { inside[static_cast<std::size_t>(t)] = chunked(1000 * (t + 1)); });
  for (Id t = 0; t < 8; ++t) EXPECT_EQ(inside[static_cast<std::size_t>(t)], chunked(1000 * (t + 1)));
}

INSTANTIATE_TEST_SUITE_P(Threads, ForEachTaskThreads, ::testing::Values(1, 2, 3));
