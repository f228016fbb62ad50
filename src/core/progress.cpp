#include "keymesh/core/progress.hpp"

#include <utility>

namespace keymesh::progress {

namespace {
// Per thread: a Python thread and the CLI's main thread each see their own.
thread_local const Hook* current = nullptr;
}  // namespace

ScopedHook::ScopedHook(Hook hook) : hook_(std::move(hook)), previous_(current) { current = &hook_; }

ScopedHook::~ScopedHook() { current = previous_; }

void report(const char* stage, double fraction) {
  if (current != nullptr && *current) (*current)(stage, fraction);
}

}  // namespace keymesh::progress
