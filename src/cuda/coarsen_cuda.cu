// Coarsening's device path (keymesh/generate/coarsen/coarsen_device.hpp) on
// the CUDA device (keymesh/device/cuda_device.cuh), compiled with --fmad=false
// as every functor of this layer: `contour --coarsen` (contour_coarsened.cuh,
// called by cuda::contour with its session's device), and coarsen_on, which
// no entry calls yet (instantiated so that the build checks it compiles for
// the GPU). ctest runs the same templates on the CPU device (DeviceCoarsen).
#include <cstdint>
#include <vector>

#include "contour_coarsened.cuh"
#include "keymesh/device/cuda_device.cuh"
#include "keymesh/generate/coarsen/coarsen_device.hpp"

namespace keymesh::generate {

template SurfaceMesh coarsen_on<device::CudaDevice>(const device::CudaDevice&, const SurfaceMesh&,
                                                    const std::vector<std::uint64_t>&, std::uint64_t, CoarsenStats*);

}  // namespace keymesh::generate

namespace keymesh::cuda {

SurfaceMesh contour_coarsened_on_gpu(const device::CudaDevice& d, const ImageGrid& grid,
                                     const generate::ContourOptions& options, generate::ContourStats* stats) {
  return generate::contour_coarsened_on(d, grid, options, stats);
}

}  // namespace keymesh::cuda
