#pragma once
// Tetrahedralization on the backend the caller names: generate's (CPU
// threads) or cuda's (an NVIDIA GPU, the same bits), chosen above both as
// for the contour (backend/contour.hpp).
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::backend {

// scheme 5: generate::tetrahedralize5; 24: generate::tetrahedralize24 (face
// centres welded by coordinates when vertex_weld). Backend::Cuda: the
// scheme's input checks (the CPU's errors), VERTEX-WELD refused by name, then
// cuda::tetrahedralize5 / 24 (InputError naming --backend cpu without a usable GPU).
UnstructuredGrid tetrahedralize(const ImageGrid& grid, int scheme, bool vertex_weld, generate::Backend backend);

// A grid of hexahedra (.vtu/.vtk): the CPU only, Backend::Cuda refused by name.
UnstructuredGrid tetrahedralize(const UnstructuredGrid& hexes, int scheme, bool vertex_weld,
                                generate::Backend backend);

}  // namespace keymesh::backend
