// Subdivision's device path (keymesh/generate/unstructured/subdivide_device.hpp)
// on the CPU device: what ctest compares with subdivide() bit for bit.
#include "keymesh/generate/unstructured/subdivide_device.hpp"

#include "keymesh/device/cpu_device.hpp"

namespace keymesh::generate {

SurfaceMesh subdivide_on_cpu_device(const SurfaceMesh& mesh, const SubdivideOptions& options) {
  return subdivide_on(device::CpuDevice{}, mesh, options);
}

UnstructuredGrid subdivide_on_cpu_device(const UnstructuredGrid& tets, const SubdivideOptions& options) {
  return subdivide_on(device::CpuDevice{}, tets, options);
}

}  // namespace keymesh::generate
