#include "unavailable.hpp"

#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"

namespace keymesh::cuda {

void refuse_gpu(const std::string& why) {
  // A dead context's reason already says "use --backend cpu or a new process".
  if (why.find("--backend cpu") != std::string::npos) throw InputError("--backend cuda: " + why);
  throw InputError("--backend cuda: " + why + " (use --backend cpu)");
}

void require_gpu() {
  std::string why;
  if (!available(&why)) refuse_gpu(why);
}

}  // namespace keymesh::cuda
