// The CUDA backend's entry points when keymesh is built without CUDA
// (KEYMESH_CUDA=OFF or no nvcc): every call says so by name.
#include "keymesh/cuda/backend.hpp"
#include "keymesh/cuda/device_contour.hpp"

#if !defined(KEYMESH_HAVE_CUDA)

#include "contour_limits.hpp"
#include "keymesh/core/error.hpp"

namespace keymesh::cuda {

bool compiled() { return false; }

bool available(std::string* why) {
  if (why) *why = "keymesh was built without the CUDA backend (KEYMESH_CUDA=OFF or no nvcc)";
  return false;
}

SurfaceMesh contour(const ImageGrid&, const generate::ContourOptions& options, generate::ContourStats*) {
  check_gpu_options(options);  // as the GPU build refuses them, before the device is considered
  throw InputError("--backend cuda: keymesh was built without the CUDA backend (KEYMESH_CUDA=OFF or no nvcc)");
}

DeviceMesh contour_device(const DeviceVolume& volume, const generate::ContourOptions& options,
                          generate::ContourStats*) {
  check_device_volume(volume, options);  // as the GPU build refuses them, before the device is considered
  throw InputError("--backend cuda: keymesh was built without the CUDA backend (KEYMESH_CUDA=OFF or no nvcc)");
}

}  // namespace keymesh::cuda

#endif
