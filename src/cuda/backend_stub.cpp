// The CUDA backend's entry points when keymesh is built without CUDA
// (KEYMESH_CUDA=OFF or no nvcc): every call says so by name, naming --backend cpu.
#include "keymesh/cuda/backend.hpp"
#include "keymesh/cuda/device_contour.hpp"
#include "keymesh/cuda/surfaces.hpp"
#include "keymesh/cuda/unstructured.hpp"

#if !defined(KEYMESH_HAVE_CUDA)

#include "contour_limits.hpp"
#include "keymesh/generate/labels/labels_device.hpp"
#include "unavailable.hpp"

namespace keymesh::cuda {

namespace {
constexpr const char* kBuiltWithout = "keymesh was built without the CUDA backend (KEYMESH_CUDA=OFF or no nvcc)";
}  // namespace

bool compiled() { return false; }

bool available(std::string* why) {
  if (why) *why = kBuiltWithout;
  return false;
}

SurfaceMesh contour(const ImageGrid&, const generate::ContourOptions& options, generate::ContourStats*) {
  check_gpu_options(options);  // as the GPU build refuses them, before the device is considered
  refuse_gpu(kBuiltWithout);
}

DeviceMesh contour_device(const DeviceVolume& volume, const generate::ContourOptions& options,
                          generate::ContourStats*) {
  check_device_volume(volume, options);  // as the GPU build refuses them, before the device is considered
  refuse_gpu(kBuiltWithout);
}

// The unstructured generators: their input checks are the backend layer's
// (src/backend/), made before it calls these.
SurfaceMesh contour_tets(const UnstructuredGrid&, const generate::ContourOptions&, generate::ContourStats*) {
  refuse_gpu(kBuiltWithout);
}
SurfaceMesh subdivide(const SurfaceMesh&, const generate::SubdivideOptions&) { refuse_gpu(kBuiltWithout); }
UnstructuredGrid subdivide(const UnstructuredGrid&, const generate::SubdivideOptions&) { refuse_gpu(kBuiltWithout); }
UnstructuredGrid tetrahedralize5(const ImageGrid&) { refuse_gpu(kBuiltWithout); }
UnstructuredGrid tetrahedralize24(const ImageGrid&) { refuse_gpu(kBuiltWithout); }

// The dual and label surface nets: the CPU's input checks, and the label
// options the device path lacks, as the GPU build makes them.
SurfaceMesh dual(const SurfaceMesh& mesh, generate::DualStats*) {
  generate::check_dual_input(mesh);
  refuse_gpu(kBuiltWithout);
}
SurfaceMesh contour_labels(const ImageGrid& grid, const generate::LabelOptions& options, generate::LabelStats*) {
  generate::check_labels_input(grid, options);
  generate::check_device_label_options(options);
  refuse_gpu(kBuiltWithout);
}

}  // namespace keymesh::cuda

#endif
