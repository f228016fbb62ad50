// Marching tetrahedra on the GPU (keymesh/cuda/unstructured.hpp): the device
// path of keymesh/generate/unstructured/contour_tets_device.hpp on the CUDA
// device, compiled with --fmad=false as every functor of this layer.
#include "gpu_session.cuh"
#include "keymesh/cuda/unstructured.hpp"
#include "keymesh/generate/unstructured/contour_tets_device.hpp"

namespace keymesh::cuda {

SurfaceMesh contour_tets(const UnstructuredGrid& tets, const generate::ContourOptions& options,
                         generate::ContourStats* stats) {
  generate::check_tet_contour_input(tets, options);  // the CPU's refusals come first, with or without a GPU
  return run_on_gpu([&](const device::CudaDevice& d) { return generate::contour_tets_on(d, tets, options, stats); });
}

}  // namespace keymesh::cuda
