// The voxel contour's device path (keymesh/generate/contour/contour_device.hpp)
// on the CPU device: what ctest compares with contour() bit for bit.
#include "keymesh/generate/contour/contour_device.hpp"
#include "keymesh/generate/contour/contour_device_plans.hpp"

#include <string>

#include "keymesh/device/cpu_device.hpp"
#include "keymesh/generate/coarsen/coarsen_device.hpp"

namespace keymesh::generate {

namespace {

[[noreturn]] void not_on_device_path(const std::string& what) {
  throw InputError("contour: " + what + " is not available on the device path (--backend cuda) yet (use --backend cpu)");
}

}  // namespace

void check_device_contour_options(const ContourOptions& opt) {
  if (opt.weld == ContourWeld::VertexWeld) not_on_device_path("VERTEX-WELD (--weld vertexweld)");
  check_device_plan_options(opt);
}

void check_device_plan_options(const ContourOptions& opt) {
  if (opt.history) not_on_device_path("per-point history (--history)");
  if (opt.output_arrays) not_on_device_path("writing into arrays the caller owns (output_arrays)");
  if (opt.total_planes) not_on_device_path("streamed (slab) contouring");
  if (opt.ghost_below || opt.ghost_above) not_on_device_path("a grid with ghost planes");
}

void refuse_device_coarsen(const ContourOptions& opt, const char* entry) {
  if (opt.coarsen)
    throw InputError(std::string("contour: coarsening (--coarsen) is not available through ") + entry +
                     " (the device path's contour_coarsened_on coarsens)");
}

SurfaceMesh contour_on_cpu_device(const ImageGrid& grid, const ContourOptions& options, ContourStats* stats,
                                  DeviceKeys keys) {
  if (options.coarsen) return contour_coarsened_on_cpu_device(grid, options, stats, keys);
  return contour_on(device::CpuDevice{}, grid, options, stats, keys);
}

}  // namespace keymesh::generate
