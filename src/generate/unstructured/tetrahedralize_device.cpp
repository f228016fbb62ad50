// The tetrahedralizations' device paths
// (keymesh/generate/unstructured/tetrahedralize_device.hpp) on the CPU device:
// what ctest compares with tetrahedralize5(grid) and tetrahedralize24(grid) bit for bit.
#include "keymesh/generate/unstructured/tetrahedralize_device.hpp"

#include "keymesh/device/cpu_device.hpp"

namespace keymesh::generate {

UnstructuredGrid tetrahedralize5_on_cpu_device(const ImageGrid& grid) {
  return tetrahedralize5_on(device::CpuDevice{}, grid);
}

UnstructuredGrid tetrahedralize24_on_cpu_device(const ImageGrid& grid) {
  return tetrahedralize24_on(device::CpuDevice{}, grid);
}

}  // namespace keymesh::generate
