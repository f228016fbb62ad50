#pragma once
// Subdivision on the backend the caller names: generate::subdivide (CPU
// threads) or cuda::subdivide (an NVIDIA GPU, the same bits). The choice is
// made above generate and cuda, as for the contour (backend/contour.hpp).
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"

namespace keymesh::backend {

// Backend::Cpu: generate::subdivide. Backend::Cuda: subdivide()'s input
// checks (the same InputError), VERTEX-WELD refused by name, then
// cuda::subdivide (InputError naming --backend cpu without a usable GPU).
SurfaceMesh subdivide(const SurfaceMesh& mesh, const generate::SubdivideOptions& options, generate::Backend backend);
UnstructuredGrid subdivide(const UnstructuredGrid& tets, const generate::SubdivideOptions& options,
                           generate::Backend backend);

}  // namespace keymesh::backend
