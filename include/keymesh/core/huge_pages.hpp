#pragma once
// Transparent huge pages for the process's large arrays.
//
// keymesh touches a few hundred MB of fresh memory per run (the volume, the
// inside bits, the soup keys, the index map). With 4 KiB pages every first
// touch is a page fault; on the 2-core VM of docs/PERFORMANCE.md that was
// 170k faults and half the run time of a 512^3 contour. glibc >= 2.35 asks
// the kernel for 2 MiB pages on its large mappings when the tunable
// glibc.malloc.hugetlb=1 is set, which must happen before the process
// starts: executables call this first thing in main() and are re-executed
// once with the tunable added (KEYMESH_HUGE_PAGES=0 turns it off).
#include <cstddef>

namespace keymesh {

// Re-executes the current program with glibc.malloc.hugetlb=1 added to
// GLIBC_TUNABLES unless it is already there or disabled; returns normally
// when nothing needs doing or the re-exec failed (then nothing changes).
void reexec_with_huge_pages(int argc, char** argv);

// Asks the kernel for transparent huge pages on the 2 MiB-aligned part of
// [data, data + bytes) (madvise(MADV_HUGEPAGE); no-op for small ranges,
// sanitizer builds, or when KEYMESH_HUGE_PAGES=0). Effective only on pages
// not yet touched: call it between allocation and first write. This is
// what a host process that was not started with the tunable (Python) needs:
// the kernel's THP mode here is `madvise`.
void advise_huge_pages(void* data, std::size_t bytes);

}  // namespace keymesh
