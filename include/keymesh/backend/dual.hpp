#pragma once
// The dual on the backend the caller names: generate::dual (CPU threads) or
// cuda::dual (an NVIDIA GPU, the same bits), chosen above both as for the
// contour (backend/contour.hpp).
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/unstructured/dual.hpp"

namespace keymesh::backend {

// Backend::Cpu: generate::dual. Backend::Cuda: dual()'s input checks (the
// same InputError), then cuda::dual (InputError naming --backend cpu without
// a usable GPU).
SurfaceMesh dual(const SurfaceMesh& mesh, generate::Backend backend, generate::DualStats* stats = nullptr);

}  // namespace keymesh::backend
