// Subdivision on the GPU (keymesh/cuda/unstructured.hpp): the device path of
// keymesh/generate/unstructured/subdivide_device.hpp on the CUDA device
// (triangles 1 -> 4, linear and Bezier; tets 1 -> 8).
#include "gpu_session.cuh"
#include "keymesh/cuda/unstructured.hpp"
#include "keymesh/generate/unstructured/subdivide_device.hpp"

namespace keymesh::cuda {

SurfaceMesh subdivide(const SurfaceMesh& mesh, const generate::SubdivideOptions& options) {
  generate::device_subdivide::check_input(mesh, options);  // refused before the device is considered
  return run_on_gpu([&](const device::CudaDevice& d) { return generate::subdivide_on(d, mesh, options); });
}

UnstructuredGrid subdivide(const UnstructuredGrid& tets, const generate::SubdivideOptions& options) {
  generate::device_subdivide::check_input(tets, options);
  return run_on_gpu([&](const device::CudaDevice& d) { return generate::subdivide_on(d, tets, options); });
}

}  // namespace keymesh::cuda
