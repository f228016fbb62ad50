// Marching tetrahedra's device path (keymesh/generate/unstructured/contour_tets_device.hpp)
// on the CPU device: what ctest compares with contour(tets) bit for bit.
#include "keymesh/generate/unstructured/contour_tets_device.hpp"

#include "keymesh/device/cpu_device.hpp"

namespace keymesh::generate {

SurfaceMesh contour_tets_on_cpu_device(const UnstructuredGrid& tets, const ContourOptions& options,
                                       ContourStats* stats) {
  return contour_tets_on(device::CpuDevice{}, tets, options, stats);
}

}  // namespace keymesh::generate
