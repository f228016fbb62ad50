#include "keymesh/core/retained_blocks.hpp"

#include <pthread.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <new>
#include <thread>
#include <unordered_map>
#include <vector>

#include "keymesh/core/huge_pages.hpp"

namespace keymesh::retained_blocks {

namespace {

using Clock = std::chrono::steady_clock;
constexpr std::size_t kPage = 4096, kHuge = std::size_t{2} << 20;

// A request's mapping: rounded up to an eighth of its power of two (at most
// 12.5 % more address space, pages past the request never touched), so that
// a later request a little larger still fits the block.
std::size_t block_size(std::size_t bytes) {
  const auto k = static_cast<int>(std::bit_width(bytes - 1));  // 2^k >= bytes
  const std::size_t step = std::max(kPage, std::size_t{1} << (k > 4 ? k - 4 : 0));
  return (bytes + step - 1) / step * step;
}

// A fresh mapping of `size` bytes starting on a 2 MiB boundary, so that huge
// pages can back all of it.
void* map_block(std::size_t size) {
  const std::size_t span = size + kHuge;
  void* p = ::mmap(nullptr, span, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  const auto begin = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t first = (begin + kHuge - 1) & ~(kHuge - 1), end = begin + span, last = first + size;
  if (first > begin) ::munmap(p, first - begin);
  if (end > last) ::munmap(reinterpret_cast<void*>(last), end - last);
  advise_huge_pages(reinterpret_cast<void*>(first), size);
  return reinterpret_cast<void*>(first);
}

struct Block {
  void* data;
  std::size_t size;
  Clock::time_point freed;
};

std::size_t default_limit() {
  if (const char* v = std::getenv("KEYMESH_RETAINED_MEMORY_MB")) {
    char* end = nullptr;
    const unsigned long long mb = std::strtoull(v, &end, 10);
    if (v[0] >= '0' && v[0] <= '9' && *end == '\0') return static_cast<std::size_t>(mb) << 20;
  }
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  const std::size_t physical = pages > 0 && page > 0 ? static_cast<std::size_t>(pages) * page : 0;
  return std::min(std::size_t{1} << 30, physical / 8);
}

struct Pool {
  std::mutex mutex;
  std::vector<Block> kept;                       // oldest first
  std::unordered_map<void*, std::size_t> lent;   // blocks in use, by address: their size
  std::size_t kept_bytes = 0, limit = default_limit(), reused = 0, mapped = 0;
  double seconds = 10;
  std::condition_variable changed;  // wakes the reaper: a block kept, the limits changed
  bool reaper_running = false;
  int keeping_nothing = 0;     // KeepNothing scopes alive
  bool forked_child = false;  // a fork's child starts no thread (blocks there go on calls)

  Pool() {
    // A fork while another thread holds the lock would leave the child's
    // copy locked forever: hold it across the fork instead. The child has
    // no reaper thread (fork copies only the caller) and starts none: a
    // multi-threaded process's child should not create threads (POSIX
    // allows only async-signal-safe calls there; ThreadSanitizer dies).
    ::pthread_atfork([] { pool().mutex.lock(); }, [] { pool().mutex.unlock(); },
                     [] {
                       pool().reaper_running = false;
                       pool().forked_child = true;
                       pool().mutex.unlock();
                     });
  }
  // Never destroyed: arrays freed by static destructors still come back here.
  static Pool& pool() {
    static Pool* p = new Pool();
    return *p;
  }

  // How long a block is kept unused (bounded, so that a due time never
  // overflows the clock).
  Clock::duration keep_for() const {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::min(seconds, 1e7)));
  }

  // Unmaps the oldest blocks while past the size limit (0 in a KeepNothing
  // scope), and those kept `seconds` or longer.
  void expire() noexcept {
    const auto now = Clock::now();
    const std::size_t bound = keeping_nothing > 0 ? 0 : limit;
    std::size_t n = 0;
    for (; n < kept.size() && (kept_bytes > bound || now - kept[n].freed >= keep_for()); ++n) {
      ::munmap(kept[n].data, kept[n].size);
      kept_bytes -= kept[n].size;
    }
    kept.erase(kept.begin(), kept.begin() + static_cast<std::ptrdiff_t>(n));
  }

  // With the lock held, after a block is kept: a thread unmaps blocks once
  // they have been kept `seconds`, so that a process which stops calling
  // keymesh (a Python session after its last contour) gets the memory back;
  // expire() alone runs only on calls. One thread at a time, gone when
  // nothing is kept. Without a thread (creating one failed) blocks still
  // go on the next call.
  void wake_reaper() noexcept {
    if (reaper_running) {
      changed.notify_one();
      return;
    }
    if (forked_child) return;
    try {
      std::thread([this] { reap(); }).detach();
      reaper_running = true;
    } catch (...) {
    }
  }
  void reap() {
    std::unique_lock lock(mutex);
    for (expire(); !kept.empty(); expire()) changed.wait_until(lock, kept.front().freed + keep_for());
    reaper_running = false;
  }
};

}  // namespace

void* acquire(std::size_t bytes) {
  Pool& p = Pool::pool();
  void* kept = nullptr;
  {
    std::lock_guard lock(p.mutex);
    p.expire();
    // The smallest kept block that holds the request and is not more than
    // twice its size (a far larger one is kept for a larger request).
    std::size_t best = p.kept.size();
    for (std::size_t k = 0; k < p.kept.size(); ++k) {
      const std::size_t size = p.kept[k].size;
      if (size >= bytes && size / 2 <= bytes && (best == p.kept.size() || size < p.kept[best].size)) best = k;
    }
    if (best < p.kept.size()) {
      const Block b = p.kept[best];
      p.lent.emplace(b.data, b.size);  // first: it may throw
      p.kept.erase(p.kept.begin() + static_cast<std::ptrdiff_t>(best));
      p.kept_bytes -= b.size;
      ++p.reused;
      kept = b.data;
    }
  }
  if (kept) return kept;
  const std::size_t size = block_size(bytes);
  void* data = map_block(size);
  std::lock_guard lock(p.mutex);
  try {
    p.lent.emplace(data, size);
  } catch (...) {
    ::munmap(data, size);
    throw;
  }
  ++p.mapped;
  return data;
}

void release(void* block, std::size_t bytes) noexcept {
  if (!block) return;
  Pool& p = Pool::pool();
  std::lock_guard lock(p.mutex);
  const auto it = p.lent.find(block);
  const std::size_t size = it != p.lent.end() ? it->second : block_size(bytes);
  if (it != p.lent.end()) p.lent.erase(it);
  // A block past the limit alone would push every other block out.
  bool keep = size <= p.limit && p.keeping_nothing == 0;
  if (keep) try {
      p.kept.push_back({block, size, Clock::now()});
      p.kept_bytes += size;
    } catch (const std::bad_alloc&) {
      keep = false;
    }
  if (!keep) ::munmap(block, size);
  p.expire();
  if (!p.kept.empty()) p.wake_reaper();
}

std::size_t release_all() noexcept {
  Pool& p = Pool::pool();
  std::lock_guard lock(p.mutex);
  const std::size_t bytes = p.kept_bytes;
  for (const Block& b : p.kept) ::munmap(b.data, b.size);
  p.kept.clear();
  p.kept_bytes = 0;
  return bytes;
}

Stats stats() noexcept {
  Pool& p = Pool::pool();
  std::lock_guard lock(p.mutex);
  return {p.kept_bytes, p.kept.size(), p.reused, p.mapped};
}

std::size_t limit() noexcept {
  Pool& p = Pool::pool();
  std::lock_guard lock(p.mutex);
  return p.limit;
}

double limit_seconds() noexcept {
  Pool& p = Pool::pool();
  std::lock_guard lock(p.mutex);
  return p.seconds;
}

void set_limits(std::size_t bytes, double seconds) noexcept {
  Pool& p = Pool::pool();
  std::lock_guard lock(p.mutex);
  p.limit = bytes, p.seconds = seconds;
  p.expire();
  p.changed.notify_one();  // a sleeping reaper's due time may have moved
}

void begin_keep_nothing() noexcept {
  Pool& p = Pool::pool();
  std::lock_guard lock(p.mutex);
  ++p.keeping_nothing;
  p.expire();
}

void end_keep_nothing() noexcept {
  Pool& p = Pool::pool();
  std::lock_guard lock(p.mutex);
  if (p.keeping_nothing > 0) --p.keeping_nothing;
}

}  // namespace keymesh::retained_blocks
