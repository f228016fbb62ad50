#pragma once
// Transparent huge pages for the process's large arrays.
//
// keymesh touches a few hundred MB of fresh memory per run (the volume, the
// inside bits, the soup keys, the index map). With 4 KiB pages every first
// touch is a page fault; on the 2-core VM of docs/PERFORMANCE.md that was
// 170k faults and half the run time of a 512^3 contour. glibc >= 2.35 asks
// the kernel for 2 MiB pages on its large mappings when the tunable
// glibc.malloc.hugetlb=1 is set, which must happen before the process
// starts: executables re-execute themselves once with the tunable added
// (KEYMESH_HUGE_PAGES=0 turns it off), from the dynamic loader's preinit
// step (KEYMESH_REEXEC_WITH_HUGE_PAGES_AT_START), so that the start thrown
// away runs no library's constructor.
#include <cstddef>

namespace keymesh {

// Re-executes the current program with glibc.malloc.hugetlb=1 added to
// GLIBC_TUNABLES unless it is already there or disabled (KEYMESH_HUGE_PAGES=0);
// returns normally when nothing needs doing or the re-exec failed (then
// nothing changes). Reads the environment from `envp` alone, calls no
// getenv or setenv: it runs before libc has set `environ` up.
void reexec_with_huge_pages(int argc, char** argv, char** envp);

// The environment of that re-exec: `envp` with glibc.malloc.hugetlb=1 added
// to GLIBC_TUNABLES (in place, or a new entry) and KEYMESH_HUGE_PAGES_REEXEC=1
// added, as one malloc'ed block (std::free it); null when no re-exec is due
// (KEYMESH_HUGE_PAGES=0, the tunable already set, a re-exec already tried)
// or memory is short.
char** huge_pages_environment(char* const* envp);

// Put once at namespace scope in one source file of an executable: an ELF
// .preinit_array entry, which the dynamic loader calls with argc, argv and
// envp before any shared library's constructor (MPI's, libstdc++'s) and
// before the executable's own. A shared object cannot carry one (the
// Python module is started by Python: it never re-executes). Empty in
// sanitizer builds, whose runtimes are not set up at that point.
#if defined(KEYMESH_NO_HUGE_PAGES) || defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define KEYMESH_REEXEC_WITH_HUGE_PAGES_AT_START() static_assert(true)
#else
#define KEYMESH_REEXEC_WITH_HUGE_PAGES_AT_START()                                                          \
  [[gnu::section(".preinit_array"), gnu::used]] static void (*const keymesh_reexec_at_start)(int, char**, \
                                                                                              char**) =   \
      &::keymesh::reexec_with_huge_pages
#endif

// Asks the kernel for transparent huge pages on the 2 MiB-aligned part of
// [data, data + bytes) (madvise(MADV_HUGEPAGE); no-op for small ranges,
// sanitizer builds, or when KEYMESH_HUGE_PAGES=0). Effective only on pages
// not yet touched: call it between allocation and first write. This is
// what a host process that was not started with the tunable (Python) needs:
// the kernel's THP mode here is `madvise`.
void advise_huge_pages(void* data, std::size_t bytes);

}  // namespace keymesh
