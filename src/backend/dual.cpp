#include "keymesh/backend/dual.hpp"

#include "keymesh/cuda/surfaces.hpp"

namespace keymesh::backend {

SurfaceMesh dual(const SurfaceMesh& mesh, generate::Backend backend, generate::DualStats* stats) {
  if (backend != generate::Backend::Cuda) return generate::dual(mesh, stats);
  generate::check_dual_input(mesh);  // the input is refused as the CPU refuses it, before the GPU is asked for
  return cuda::dual(mesh, stats);
}

}  // namespace keymesh::backend
