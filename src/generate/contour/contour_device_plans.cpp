// The voxel contour's device plans (keymesh/generate/contour/contour_device_plans.hpp)
// on the CPU device: what ctest compares with contour() bit for bit.
#include "keymesh/generate/contour/contour_device_plans.hpp"

#include "keymesh/device/cpu_device.hpp"

namespace keymesh::generate {

DevicePlan device_plan_for(ContourWeld weld) {
  switch (weld) {
    case ContourWeld::KeyReduceSort: return DevicePlan::Sort;
    case ContourWeld::VertexWeld: return DevicePlan::VertexWeld;
    case ContourWeld::KeyReduce: break;
  }
  return DevicePlan::Structured;
}

SurfaceMesh contour_plan_on_cpu_device(const ImageGrid& grid, const ContourOptions& options, DevicePlan plan,
                                       ContourStats* stats, DeviceKeys keys) {
  return contour_plan_on(device::CpuDevice{}, grid, options, plan, stats, keys);
}

}  // namespace keymesh::generate
