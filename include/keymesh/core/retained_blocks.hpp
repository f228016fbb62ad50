#pragma once
// Large blocks of memory kept mapped after their array is freed, handed to
// the next large array instead of fresh pages.
//
// On the VMs keymesh is measured on, a page's first touch is the most
// expensive thing an output costs: the kernel zeroes it, and when the host
// has taken the guest's free memory back (the balloon / DAMON reclaim of
// these machines) the zeroing itself faults on the host. A Python session
// contouring one volume after another freed a 64 MB output and mapped a new
// one on every call: the same call took 30 ms or 70 ms depending on which
// pages the kernel gave (measured 2026-11-24, ch2better, bench/dense.py).
// Arrays of kMinBytes or more (core/array.hpp's Array, hence every mesh
// output and the Python module's arrays) take their storage from here; a
// block freed is kept, up to limit() bytes, for limit_seconds() unless used
// again, and the next array that fits (its size up to twice the request)
// gets it, pages already mapped. Blocks are whole mappings, 2 MiB aligned,
// with huge pages asked for (core/huge_pages.hpp). A thread of its own
// unmaps a block once it has been kept that long, so a process that stops
// calling keymesh gets its memory back.
//
// KEYMESH_RETAINED_MEMORY_MB sets the limit (0: every block unmapped when
// freed, as before); sanitizer builds never keep a block (ASan must see a
// use after free). release_all() unmaps what is kept now
// (keymesh.release_memory() in Python).
#include <cstddef>

namespace keymesh::retained_blocks {

// Whether Array takes large blocks from here (not in sanitizer builds).
#ifdef KEYMESH_NO_RETAINED_BLOCKS
inline constexpr bool kInUse = false;
#else
inline constexpr bool kInUse = true;
#endif

// Requests below this go to operator new: a mapping of their own would cost
// more than it saves.
inline constexpr std::size_t kMinBytes = std::size_t{4} << 20;

// A block of at least `bytes` (>= kMinBytes), page aligned, contents
// unspecified (zeros when fresh, an earlier array's bytes when kept).
// Throws std::bad_alloc when the kernel refuses the mapping.
void* acquire(std::size_t bytes);

// Gives back a block acquire() returned for `bytes`: kept for reuse within
// the limit, unmapped otherwise.
void release(void* block, std::size_t bytes) noexcept;

// Unmaps every block kept; returns their bytes.
std::size_t release_all() noexcept;

struct Stats {
  std::size_t kept_bytes = 0;    // in blocks waiting for reuse
  std::size_t kept_blocks = 0;
  std::size_t reused = 0;        // acquire() calls served by a kept block (since the start)
  std::size_t mapped = 0;        // acquire() calls that mapped fresh memory
};
Stats stats() noexcept;

// The limit on kept bytes and how long an unused block is kept. The
// defaults: the smaller of 1 GiB and an eighth of physical memory
// (KEYMESH_RETAINED_MEMORY_MB overrides it), 10 seconds. Setting them
// releases what no longer fits.
std::size_t limit() noexcept;
double limit_seconds() noexcept;
void set_limits(std::size_t bytes, double seconds) noexcept;

// While one lives, nothing is kept (what was kept is unmapped; limit() and
// limit_seconds() are left as they are): a run held to a memory budget
// (--memory-limit's streamed contour and label surfaces) counts what it
// maps, and a kept block would be memory the budget does not see. Scopes
// are counted, not saved and restored, so they may overlap in any order on
// any threads (keymesh.dask runs several streamed label slabs at once).
void begin_keep_nothing() noexcept;
void end_keep_nothing() noexcept;
class KeepNothing {
 public:
  KeepNothing() noexcept { begin_keep_nothing(); }
  ~KeepNothing() { end_keep_nothing(); }
  KeepNothing(const KeepNothing&) = delete;
  KeepNothing& operator=(const KeepNothing&) = delete;
};

}  // namespace keymesh::retained_blocks
