// Label surface nets' device path (keymesh/generate/labels/labels_device.hpp):
// the host's part (the options it refuses, the scan of the volume it
// uploads) and its instantiation on the CPU device, what ctest compares
// with contour_labels() bit for bit.
#include "keymesh/generate/labels/labels_device.hpp"

#include <chrono>
#include <string>
#include <utility>

#include "keymesh/device/cpu_device.hpp"
#include "label_volume.hpp"

namespace keymesh::generate {

void check_device_label_options(const LabelOptions& options) {
  auto refuse = [](const char* option) {
    throw InputError(std::string("labels: ") + option + " is not available on the device path (use --backend cpu)");
  };
  if (options.method != LabelMethod::SurfaceNets) refuse("--method discrete-mc");
  if (options.per_label) refuse("--per-label");
  if (options.coarsen) refuse("--coarsen");
  if (options.history) refuse("per-point history (--history)");
}

ScannedLabels scan_labels_for_device(const ImageGrid& grid, const LabelOptions& options) {
  detail::check_label_options(options);
  const auto t0 = std::chrono::steady_clock::now();
  detail::LabelVolume vol = detail::scan_labels(grid, options);
  ScannedLabels sc{detail::placement(vol), std::move(vol.index), std::vector<float>(vol.values.size()),
                   vol.distinct_in_grid, static_cast<Id>(vol.selected.size()), 0.0};
  // As finish_label_mesh writes boundary_labels: each value cast to float.
  for (std::size_t l = 0; l < vol.values.size(); ++l) sc.value_of[l] = static_cast<float>(vol.values[l]);
  sc.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sc;
}

SurfaceMesh contour_labels_on_cpu_device(const ImageGrid& grid, const LabelOptions& options, LabelStats* stats,
                                         bool force_64bit_keys) {
  return contour_labels_on(device::CpuDevice{}, grid, options, stats, force_64bit_keys);
}

}  // namespace keymesh::generate
