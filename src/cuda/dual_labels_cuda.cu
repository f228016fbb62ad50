// The dual's and label surface nets' device paths instantiated on the CUDA
// device: nvcc compiles their functors (KEYMESH_HD) and the layer's launch
// glue for them, so a change that breaks either on the GPU fails the CUDA
// build (and `make gpu-check-build`), not a GPU run. No entry calls them yet:
// cuda::dual and cuda::contour_labels come with a GPU session shared with
// contour_cuda.cu (its stream, pool and stage events); ctest runs the same
// templates on the CPU device (DeviceDual, DeviceLabels).
#include "keymesh/device/cuda_device.cuh"
#include "keymesh/generate/labels/labels_device.hpp"
#include "keymesh/generate/unstructured/dual_device.hpp"

namespace keymesh::generate {

template SurfaceMesh dual_on<device::CudaDevice>(const device::CudaDevice&, const SurfaceMesh&, DualStats*);
template SurfaceMesh contour_labels_on<device::CudaDevice>(const device::CudaDevice&, const ImageGrid&,
                                                           const LabelOptions&, LabelStats*, bool);

}  // namespace keymesh::generate
