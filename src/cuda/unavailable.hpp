#pragma once
// The one line every --backend cuda run says when the GPU cannot run it (no
// CUDA build, no device, a context a fault left unusable), naming the way
// out: --backend cpu (docs/ERRORS.md). Host code, compiled in every build.
#include <string>

namespace keymesh::cuda {

// InputError "--backend cuda: <why> (use --backend cpu)" (the hint once:
// a dead context's reason says it already).
[[noreturn]] void refuse_gpu(const std::string& why);

// Returns when a usable device is present (available()); refuse_gpu(why) otherwise.
void require_gpu();

}  // namespace keymesh::cuda
