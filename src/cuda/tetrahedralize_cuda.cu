// The 5- and 24-tet tetrahedralizations of a voxel grid on the GPU
// (keymesh/cuda/unstructured.hpp): the device paths of
// keymesh/generate/unstructured/tetrahedralize_device.hpp on the CUDA device.
#include "gpu_session.cuh"
#include "keymesh/cuda/unstructured.hpp"
#include "keymesh/generate/unstructured/tetrahedralize_device.hpp"

namespace keymesh::cuda {

UnstructuredGrid tetrahedralize5(const ImageGrid& grid) {
  generate::check_tetrahedralize5_input(grid);  // refused before the device is considered
  return run_on_gpu([&](const device::CudaDevice& d) { return generate::tetrahedralize5_on(d, grid); });
}

UnstructuredGrid tetrahedralize24(const ImageGrid& grid) {
  generate::check_tetrahedralize24_input(grid);
  return run_on_gpu([&](const device::CudaDevice& d) { return generate::tetrahedralize24_on(d, grid); });
}

}  // namespace keymesh::cuda
