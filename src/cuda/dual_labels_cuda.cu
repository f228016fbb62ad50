// The dual and label surface nets on the GPU (keymesh/cuda/surfaces.hpp): their
// device paths (dual_device.hpp, labels_device.hpp) on the CUDA device, in
// gpu_session.cuh's session, compiled with --fmad=false as every functor of
// this layer. ctest runs the same templates on the CPU device (DeviceDual,
// DeviceLabels).
#include "gpu_session.cuh"
#include "keymesh/cuda/surfaces.hpp"
#include "keymesh/generate/labels/labels_device.hpp"
#include "keymesh/generate/unstructured/dual_device.hpp"

namespace keymesh::cuda {

SurfaceMesh dual(const SurfaceMesh& mesh, generate::DualStats* stats) {
  generate::check_dual_input(mesh);  // the CPU's refusals come first, with or without a GPU
  return run_on_gpu([&](const device::CudaDevice& d) { return generate::dual_on(d, mesh, stats); });
}

SurfaceMesh contour_labels(const ImageGrid& grid, const generate::LabelOptions& options,
                           generate::LabelStats* stats) {
  generate::check_labels_input(grid, options);  // the CPU's refusals, then what the device path lacks
  generate::check_device_label_options(options);
  return run_on_gpu([&](const device::CudaDevice& d) { return generate::contour_labels_on(d, grid, options, stats); });
}

}  // namespace keymesh::cuda
