// The dual's device path (keymesh/generate/unstructured/dual_device.hpp) on
// the CPU device: what ctest compares with dual() bit for bit.
#include "keymesh/generate/unstructured/dual_device.hpp"

#include "keymesh/device/cpu_device.hpp"

namespace keymesh::generate {

SurfaceMesh dual_on_cpu_device(const SurfaceMesh& mesh, DualStats* stats) {
  return dual_on(device::CpuDevice{}, mesh, stats);
}

}  // namespace keymesh::generate
