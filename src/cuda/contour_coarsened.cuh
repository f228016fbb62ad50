#pragma once
// `contour --coarsen` on the GPU (nvcc only): cuda::contour's entry
// (contour_cuda.cu) calls it with its session's device when options.coarsen
// is on; coarsen_cuda.cu compiles it, so the coarsening's kernels build in a
// file of their own.
#include "keymesh/device/cuda_device.cuh"
#include "keymesh/generate/contour/contour.hpp"

namespace keymesh::cuda {

// generate::contour_coarsened_on(d, grid, options, stats): the contour's
// device path, coarsened on the device, split on the host.
SurfaceMesh contour_coarsened_on_gpu(const device::CudaDevice& d, const ImageGrid& grid,
                                     const generate::ContourOptions& options, generate::ContourStats* stats);

}  // namespace keymesh::cuda
