#include "keymesh/core/huge_pages.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>

#include <cstdlib>
#include <cstring>
#include <string>

namespace keymesh {

void reexec_with_huge_pages(int argc, char** argv) {
  (void)argc;
#if defined(KEYMESH_NO_HUGE_PAGES) || defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  // Sanitizer and fuzzing builds: the sanitizers own malloc, and a re-exec
  // would hide the first process's reports from the test runner.
  (void)argv;
  return;
#else
  const char* off = std::getenv("KEYMESH_HUGE_PAGES");
  if (off && std::strcmp(off, "0") == 0) return;
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  std::string value = tunables ? tunables : "";
  if (value.find("glibc.malloc.hugetlb") != std::string::npos) return;
  // Mark the attempt so that a libc ignoring the tunable cannot loop us.
  if (std::getenv("KEYMESH_HUGE_PAGES_REEXEC")) return;
  value = value.empty() ? "glibc.malloc.hugetlb=1" : value + ":glibc.malloc.hugetlb=1";
  if (setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  if (setenv("KEYMESH_HUGE_PAGES_REEXEC", "1", 1) != 0) return;
  execv("/proc/self/exe", argv);
  // execv only returns on failure: carry on with ordinary pages.
  unsetenv("KEYMESH_HUGE_PAGES_REEXEC");
#endif
}

void advise_huge_pages(void* data, std::size_t bytes) {
#if defined(KEYMESH_NO_HUGE_PAGES) || defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  (void)data;
  (void)bytes;
#else
  constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
  const auto begin = reinterpret_cast<std::uintptr_t>(data);
  const std::uintptr_t first = (begin + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t last = (begin + bytes) & ~(kHuge - 1);
  if (last <= first) return;
  static const bool off = [] {
    const char* v = std::getenv("KEYMESH_HUGE_PAGES");
    return v && std::strcmp(v, "0") == 0;
  }();
  if (off) return;
  // Advice only: a kernel without THP says EINVAL and nothing changes.
  (void)madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#endif
}

}  // namespace keymesh
