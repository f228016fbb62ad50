#include "keymesh/core/huge_pages.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace keymesh {

namespace {

// The value of `name` in `envp` ("NAME=value"), or null; its entry's index
// in `at`.
const char* find_variable(char* const* envp, const char* name, std::size_t* at = nullptr) {
  const std::size_t length = std::strlen(name);
  for (std::size_t k = 0; envp && envp[k]; ++k)
    if (std::strncmp(envp[k], name, length) == 0 && envp[k][length] == '=') {
      if (at) *at = k;
      return envp[k] + length + 1;
    }
  return nullptr;
}

}  // namespace

char** huge_pages_environment(char* const* envp) {
  const char* off = find_variable(envp, "KEYMESH_HUGE_PAGES");
  if (off && std::strcmp(off, "0") == 0) return nullptr;
  std::size_t tunables_at = 0;
  const char* tunables = find_variable(envp, "GLIBC_TUNABLES", &tunables_at);
  if (tunables && std::strstr(tunables, "glibc.malloc.hugetlb")) return nullptr;
  // Mark the attempt so that a libc ignoring the tunable cannot loop us.
  if (find_variable(envp, "KEYMESH_HUGE_PAGES_REEXEC")) return nullptr;
  std::size_t count = 0;
  while (envp && envp[count]) ++count;
  const char* tunable = "glibc.malloc.hugetlb=1";
  const std::size_t old = tunables ? std::strlen(tunables) : 0;
  const std::size_t size = std::strlen("GLIBC_TUNABLES=") + old + 1 + std::strlen(tunable) + 1;
  // One block: the pointers (envp's, one more for each variable added and
  // the end), then the new GLIBC_TUNABLES entry.
  const std::size_t pointers = (count + 3) * sizeof(char*);
  char** env = static_cast<char**>(std::malloc(pointers + size));
  if (!env) return nullptr;
  char* value = reinterpret_cast<char*>(env) + pointers;
  std::snprintf(value, size, "GLIBC_TUNABLES=%s%s%s", tunables ? tunables : "", old ? ":" : "", tunable);
  std::size_t n = 0;
  for (; n < count; ++n) env[n] = envp[n];
  if (tunables) env[tunables_at] = value;
  else env[n++] = value;
  env[n++] = const_cast<char*>("KEYMESH_HUGE_PAGES_REEXEC=1");
  env[n] = nullptr;
  return env;
}

void reexec_with_huge_pages(int argc, char** argv, char** envp) {
  (void)argc;
#if defined(KEYMESH_NO_HUGE_PAGES) || defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  // Sanitizer and fuzzing builds: the sanitizers own malloc, and a re-exec
  // would hide the first process's reports from the test runner.
  (void)argv;
  (void)envp;
  return;
#else
  char** env = huge_pages_environment(envp);
  if (!env) return;
  execve("/proc/self/exe", argv, env);
  // execve only returns on failure: carry on with ordinary pages.
  std::free(env);
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
