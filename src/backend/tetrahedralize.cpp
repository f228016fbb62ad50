#include "keymesh/backend/tetrahedralize.hpp"

#include "keymesh/cuda/unstructured.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "not_on_gpu.hpp"

namespace keymesh::backend {

UnstructuredGrid tetrahedralize(const ImageGrid& grid, int scheme, bool vertex_weld, generate::Backend backend) {
  if (backend != generate::Backend::Cuda)
    return scheme == 24 ? generate::tetrahedralize24(grid, vertex_weld) : generate::tetrahedralize5(grid);
  if (scheme != 24) {
    generate::check_tetrahedralize5_input(grid);
    return cuda::tetrahedralize5(grid);
  }
  generate::check_tetrahedralize24_input(grid);
  if (vertex_weld) not_on_gpu("VERTEX-WELD (--weld vertexweld)");
  return cuda::tetrahedralize24(grid);
}

UnstructuredGrid tetrahedralize(const UnstructuredGrid& hexes, int scheme, bool vertex_weld,
                                generate::Backend backend) {
  if (backend == generate::Backend::Cuda) not_on_gpu("tetrahedralizing a grid of hexahedra (.vtu/.vtk input)");
  return scheme == 24 ? generate::tetrahedralize24(hexes, vertex_weld) : generate::tetrahedralize5(hexes);
}

}  // namespace keymesh::backend
