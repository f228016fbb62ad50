// core/retained_blocks: a freed large block is kept mapped and handed to the
// next request it fits (its bytes still there, so no fresh page was
// mapped), within the size and time limits (the time limit kept by the
// pool's own thread, with no further call), from any thread, across a
// fork; Array's large storage comes from it.
#include "keymesh/core/retained_blocks.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

#include "keymesh/core/array.hpp"

namespace rb = keymesh::retained_blocks;

namespace {

constexpr std::size_t kMiB = std::size_t{1} << 20;

// Each test starts with nothing kept and generous limits, and puts the
// process's limits back after.
class RetainedBlocks : public ::testing::Test {
 protected:
  void SetUp() override {
    limit_ = rb::limit(), seconds_ = rb::limit_seconds();
    rb::set_limits(std::size_t{1} << 30, 3600);
    rb::release_all();
  }
  void TearDown() override {
    rb::release_all();
    rb::set_limits(limit_, seconds_);
  }
  std::size_t limit_ = 0;
  double seconds_ = 0;
};

void fill(void* p, std::size_t bytes, unsigned char v) { std::memset(p, v, bytes); }
bool holds(const void* p, std::size_t bytes, unsigned char v) {
  const auto* c = static_cast<const unsigned char*>(p);
  for (std::size_t k = 0; k < bytes; k += 4093)
    if (c[k] != v) return false;
  return c[bytes - 1] == v;
}

}  // namespace

TEST_F(RetainedBlocks, AFreedBlockServesTheNextRequestWithItsPagesMapped) {
  const auto before = rb::stats();
  void* p = rb::acquire(8 * kMiB);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % (2 * kMiB), 0u);  // huge pages can back all of it
  fill(p, 8 * kMiB, 0x5a);
  rb::release(p, 8 * kMiB);
  EXPECT_EQ(rb::stats().kept_blocks, 1u);
  EXPECT_GE(rb::stats().kept_bytes, 8 * kMiB);
  void* q = rb::acquire(8 * kMiB);
  EXPECT_EQ(q, p);
  EXPECT_TRUE(holds(q, 8 * kMiB, 0x5a));  // the same pages, not fresh zeros
  EXPECT_EQ(rb::stats().kept_blocks, 0u);
  EXPECT_EQ(rb::stats().reused, before.reused + 1);
  EXPECT_EQ(rb::stats().mapped, before.mapped + 1);
  rb::release(q, 8 * kMiB);
}

TEST_F(RetainedBlocks, ABlockMoreThanTwiceTheRequestIsKeptForALargerOne) {
  void* big = rb::acquire(40 * kMiB);
  rb::release(big, 40 * kMiB);
  void* small = rb::acquire(8 * kMiB);
  EXPECT_NE(small, big);
  EXPECT_EQ(rb::stats().kept_blocks, 1u);
  void* again = rb::acquire(30 * kMiB);  // within twice: the big block
  EXPECT_EQ(again, big);
  rb::release(small, 8 * kMiB);
  rb::release(again, 30 * kMiB);
}

TEST_F(RetainedBlocks, ARequestALittleLargerFitsTheRoundedUpBlock) {
  // 10 MiB + 1 lies in (8, 16] MiB: mapped in steps of 16/16 = 1 MiB, i.e.
  // 11 MiB, so a request of 10.5 MiB later fits it.
  void* p = rb::acquire(10 * kMiB + 1);
  fill(p, 10 * kMiB + 1, 1);
  rb::release(p, 10 * kMiB + 1);
  EXPECT_EQ(rb::stats().kept_bytes, 11 * kMiB);
  void* q = rb::acquire(10 * kMiB + kMiB / 2);
  EXPECT_EQ(q, p);
  fill(q, 10 * kMiB + kMiB / 2, 2);  // every byte asked for is there
  rb::release(q, 10 * kMiB + kMiB / 2);
}

TEST_F(RetainedBlocks, TheOldestBlocksGoPastTheSizeLimit) {
  rb::set_limits(20 * kMiB, 3600);
  void* a = rb::acquire(8 * kMiB);
  void* b = rb::acquire(8 * kMiB);
  void* c = rb::acquire(8 * kMiB);
  fill(b, 8 * kMiB, 0xb), fill(c, 8 * kMiB, 0xc);
  rb::release(a, 8 * kMiB), rb::release(b, 8 * kMiB), rb::release(c, 8 * kMiB);
  EXPECT_EQ(rb::stats().kept_blocks, 2u);
  EXPECT_EQ(rb::stats().kept_bytes, 16 * kMiB);
  // a went first: the next two requests get c (the smallest fit, equal
  // sizes: the first found) and b, with their bytes.
  void* x = rb::acquire(8 * kMiB);
  void* y = rb::acquire(8 * kMiB);
  EXPECT_TRUE((x == b && y == c) || (x == c && y == b));
  EXPECT_TRUE(holds(b, 8 * kMiB, 0xb) && holds(c, 8 * kMiB, 0xc));
  // A block larger than the whole limit is not kept, and pushes nothing out.
  rb::release(x, 8 * kMiB);
  void* huge = rb::acquire(24 * kMiB);
  rb::release(huge, 24 * kMiB);
  EXPECT_EQ(rb::stats().kept_blocks, 1u);
  rb::release(y, 8 * kMiB);
}

TEST_F(RetainedBlocks, WithoutTheThreadAnOldBlockGoesOnTheNextCall) {
  // A fork's child starts no thread: there the next acquire expires a
  // block kept past the time limit, and nothing else does.
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    rb::set_limits(std::size_t{1} << 30, 0.05);
    void* p = rb::acquire(8 * kMiB);
    rb::release(p, 8 * kMiB);
    std::this_thread::sleep_for(std::chrono::milliseconds(120));
    const bool still_kept = rb::stats().kept_blocks == 1;  // no thread took it
    void* q = rb::acquire(4 * kMiB);
    const bool gone = rb::stats().kept_blocks == 0;
    rb::release(q, 4 * kMiB);
    ::_exit(still_kept && gone ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

TEST_F(RetainedBlocks, AKeptBlockGoesAfterTheTimeLimitWithNoFurtherCall) {
  rb::set_limits(std::size_t{1} << 30, 0.3);
  void* p = rb::acquire(8 * kMiB);
  rb::release(p, 8 * kMiB);
  EXPECT_EQ(rb::stats().kept_blocks, 1u);
  // No acquire or release from here on (stats() expires nothing): only
  // the pool's own thread can unmap the block.
  for (int waited = 0; waited < 100 && rb::stats().kept_blocks != 0; ++waited)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(rb::stats().kept_blocks, 0u);
  EXPECT_EQ(rb::stats().kept_bytes, 0u);
}

TEST_F(RetainedBlocks, ReleaseAllUnmapsEverythingKept) {
  void* p = rb::acquire(8 * kMiB);
  void* q = rb::acquire(6 * kMiB);
  rb::release(p, 8 * kMiB), rb::release(q, 6 * kMiB);
  const std::size_t kept = rb::stats().kept_bytes;
  EXPECT_GE(kept, 14 * kMiB);
  EXPECT_EQ(rb::release_all(), kept);
  EXPECT_EQ(rb::stats().kept_bytes, 0u);
  EXPECT_EQ(rb::stats().kept_blocks, 0u);
  rb::set_limits(0, 3600);  // a limit of 0 keeps nothing
  void* r = rb::acquire(8 * kMiB);
  rb::release(r, 8 * kMiB);
  EXPECT_EQ(rb::stats().kept_blocks, 0u);
}

TEST_F(RetainedBlocks, NothingIsKeptWhileAKeepNothingLives) {
  void* p = rb::acquire(8 * kMiB);
  rb::release(p, 8 * kMiB);
  ASSERT_EQ(rb::stats().kept_blocks, 1u);
  {
    const rb::KeepNothing scope;
    EXPECT_EQ(rb::stats().kept_blocks, 0u);  // what was kept is unmapped
    void* q = rb::acquire(8 * kMiB);
    rb::release(q, 8 * kMiB);
    EXPECT_EQ(rb::stats().kept_blocks, 0u);
  }
  EXPECT_EQ(rb::limit(), std::size_t{1} << 30);  // the limits come back
  EXPECT_EQ(rb::limit_seconds(), 3600);
  void* r = rb::acquire(8 * kMiB);
  rb::release(r, 8 * kMiB);
  EXPECT_EQ(rb::stats().kept_blocks, 1u);
}

// keymesh.dask runs streamed label slabs on several threads at once: scopes
// that end out of order once left the limit at 0 (each saved the other's 0).
TEST_F(RetainedBlocks, OverlappingKeepNothingScopesLeaveTheLimitsAlone) {
  auto first = std::make_unique<rb::KeepNothing>();
  auto second = std::make_unique<rb::KeepNothing>();
  first.reset();  // the first ends before the second
  void* q = rb::acquire(8 * kMiB);
  rb::release(q, 8 * kMiB);
  EXPECT_EQ(rb::stats().kept_blocks, 0u);  // the second still keeps nothing
  second.reset();
  EXPECT_EQ(rb::limit(), std::size_t{1} << 30);
  EXPECT_EQ(rb::limit_seconds(), 3600);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([] {
      for (int round = 0; round < 200; ++round) const rb::KeepNothing scope;
    });
  for (auto& t : threads) t.join();
  void* r = rb::acquire(8 * kMiB);
  rb::release(r, 8 * kMiB);
  EXPECT_EQ(rb::stats().kept_blocks, 1u);  // kept again once every scope ended
}

TEST_F(RetainedBlocks, ThreadsNeverShareABlock) {
  std::vector<std::thread> threads;
  std::vector<int> failures(4, 0);
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([t, &failures] {
      for (int round = 0; round < 50; ++round) {
        const std::size_t bytes = (4 + static_cast<std::size_t>((t + round) % 5)) * kMiB;
        void* p = rb::acquire(bytes);
        fill(p, bytes, static_cast<unsigned char>(t + 1));
        std::this_thread::yield();
        if (!holds(p, bytes, static_cast<unsigned char>(t + 1))) ++failures[t];
        rb::release(p, bytes);
      }
    });
  for (auto& th : threads) th.join();
  for (int t = 0; t < 4; ++t) EXPECT_EQ(failures[t], 0) << "thread " << t;
}

TEST_F(RetainedBlocks, AForkedChildCanAcquireAndRelease) {
  void* p = rb::acquire(8 * kMiB);
  rb::release(p, 8 * kMiB);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    void* q = rb::acquire(8 * kMiB);
    rb::release(q, 8 * kMiB);
    ::_exit(q == p ? 0 : 1);  // the child's copy of the kept block
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

TEST_F(RetainedBlocks, AnArraysLargeStorageComesFromTheKeptBlocks) {
  if (!rb::kInUse) GTEST_SKIP() << "sanitizer build: Array uses operator new";
  const auto before = rb::stats();
  const float* storage = nullptr;
  {
    keymesh::Array<float> a(4 * kMiB);  // 16 MiB
    a[0] = 1;
    storage = a.data();
  }
  EXPECT_EQ(rb::stats().kept_blocks, 1u);
  keymesh::Array<float> b(4 * kMiB);
  EXPECT_EQ(b.data(), storage);
  EXPECT_EQ(b[0], 1.0f);  // unwritten, as Array leaves it: the freed array's value
  keymesh::Array<float> small(1000);  // below kMinBytes: operator new
  EXPECT_EQ(rb::stats().mapped, before.mapped + 1);
  EXPECT_EQ(rb::stats().reused, before.reused + 1);
}
