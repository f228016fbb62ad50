// Coarsening's device path (keymesh/generate/coarsen/coarsen_device.hpp) on
// the CPU device: what ctest compares with coarsen() and contour --coarsen
// bit for bit.
#include "keymesh/generate/coarsen/coarsen_device.hpp"

#include "keymesh/device/cpu_device.hpp"

namespace keymesh::generate {

SurfaceMesh coarsen_on_cpu_device(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys,
                                  std::uint64_t key_range, CoarsenStats* stats) {
  return coarsen_on(device::CpuDevice{}, mesh, keys, key_range, stats);
}

SurfaceMesh contour_coarsened_on_cpu_device(const ImageGrid& grid, const ContourOptions& options, ContourStats* stats,
                                            DeviceKeys keys) {
  return contour_coarsened_on(device::CpuDevice{}, grid, options, stats, keys);
}

}  // namespace keymesh::generate
