#pragma once
// Progress of long operations, and the way to abandon them.
//
// A long operation calls report(stage, fraction) between its stages (and
// between chunks of a long stage) on the thread that called it, never from
// inside a parallel loop. The hook installed on that thread, if any, is
// called: the CLI prints the stage on stderr, the Python module calls the
// user's progress= callback and checks for Ctrl-C. A hook may throw to
// abandon the operation: the library is exception-safe (RAII buffers, output
// files written under a temporary name), so an abandoned call leaves nothing
// half-built behind.
#include <functional>

namespace keymesh::progress {

// stage: a short name ("classify", "weld", "subdivide level 2/3");
// fraction: of the whole operation done, in [0, 1].
using Hook = std::function<void(const char* stage, double fraction)>;

// Installs a hook on the calling thread for its lifetime (the previous one
// is restored after; hooks nest).
class ScopedHook {
 public:
  explicit ScopedHook(Hook hook);
  ~ScopedHook();
  ScopedHook(const ScopedHook&) = delete;
  ScopedHook& operator=(const ScopedHook&) = delete;

 private:
  Hook hook_;
  const Hook* previous_;
};

// Calls the calling thread's hook, if one is installed.
void report(const char* stage, double fraction);

}  // namespace keymesh::progress
