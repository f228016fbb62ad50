// Label surface nets' device path (labels_device.hpp) on the CPU device:
// what ctest compares with contour_labels() bit for bit; and the refusal of
// the options the path lacks.
#include "labels_device.hpp"

#include "keymesh/device/cpu_device.hpp"

namespace keymesh::generate {

void check_device_label_options(const LabelOptions& options) {
  auto refuse = [](const char* option) {
    throw InputError(std::string("labels: ") + option +
                     " is not available on the device path (use --backend cpu)");
  };
  if (options.method != LabelMethod::SurfaceNets) refuse("--method discrete-mc");
  if (options.per_label) refuse("--per-label");
  if (options.coarsen) refuse("--coarsen");
}

SurfaceMesh contour_labels_on_cpu_device(const ImageGrid& grid, const LabelOptions& options, LabelStats* stats,
                                         bool force_64bit_keys) {
  return contour_labels_on(device::CpuDevice{}, grid, options, stats, force_64bit_keys);
}

}  // namespace keymesh::generate
