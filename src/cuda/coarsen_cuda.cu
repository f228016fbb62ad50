// Coarsening's device path (keymesh/generate/coarsen/coarsen_device.hpp)
// instantiated for the CUDA device (keymesh/device/cuda_device.cuh): the
// functors ctest runs bit for bit against coarsen() on the CPU device,
// compiled for the GPU with --fmad=false, so that the build checks they
// compile there. Not wired to an entry yet: cuda::contour still refuses
// --coarsen (contour_limits.cpp); the next step calls contour_coarsened_on
// with its session's device, as it calls contour_on.
#include <cstdint>
#include <vector>

#include "keymesh/device/cuda_device.cuh"
#include "keymesh/generate/coarsen/coarsen_device.hpp"

namespace keymesh::generate {

template SurfaceMesh coarsen_on<device::CudaDevice>(const device::CudaDevice&, const SurfaceMesh&,
                                                    const std::vector<std::uint64_t>&, std::uint64_t, CoarsenStats*);
template SurfaceMesh contour_coarsened_on<device::CudaDevice>(const device::CudaDevice&, const ImageGrid&,
                                                              const ContourOptions&, ContourStats*, DeviceKeys);

}  // namespace keymesh::generate
