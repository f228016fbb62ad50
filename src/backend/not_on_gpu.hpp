#pragma once
// The backend layer's refusal of what a generator's GPU path lacks, by name,
// before the device is considered (docs/ERRORS.md).
#include <string>

#include "keymesh/core/error.hpp"

namespace keymesh::backend {

// InputError "--backend cuda: <what> is not available on the GPU yet (use --backend cpu)".
[[noreturn]] inline void not_on_gpu(const std::string& what) {
  throw InputError("--backend cuda: " + what + " is not available on the GPU yet (use --backend cpu)");
}

}  // namespace keymesh::backend
