#pragma once
// The dual and label surface nets on an NVIDIA GPU. Each runs its device
// path (generate/unstructured/dual_device.hpp, generate/labels/labels_device.hpp:
// the code ctest runs bit for bit against the CPU on the CPU device) on the
// CUDA device (src/cuda/dual_labels_cuda.cu), host data in and out; the
// output is the CPU's, bit for bit. (`contour --coarsen` is cuda::contour's,
// keymesh/cuda/backend.hpp.)
//
// Each runs its generator's input checks first (the CPU's InputError), then
// refuses by name what its device path lacks (labels: discrete-mc,
// --per-label, --coarsen, smoothing), then InputError "--backend cuda: <why>
// (use --backend cpu)" when no usable device is present or keymesh was built
// without CUDA (src/cuda/backend_stub.cpp); out of device memory is a
// LimitError naming --backend cpu.
#include "keymesh/generate/labels/labels.hpp"
#include "keymesh/generate/unstructured/dual.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::cuda {

// generate::dual on the GPU, statistics included.
SurfaceMesh dual(const SurfaceMesh& mesh, generate::DualStats* stats = nullptr);

// generate::contour_labels on the GPU: surface nets, one network, no
// smoothing, no coarsening (the rest refused by name).
SurfaceMesh contour_labels(const ImageGrid& grid, const generate::LabelOptions& options,
                           generate::LabelStats* stats = nullptr);

}  // namespace keymesh::cuda
