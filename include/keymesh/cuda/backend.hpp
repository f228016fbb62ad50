#pragma once
// The compute backend: CPU threads (OpenMP) or an NVIDIA GPU (CUDA, when
// keymesh was built with KEYMESH_CUDA and a device is present).
#include <string>

#include "keymesh/generate/contour/contour.hpp"

namespace keymesh::cuda {

// True when the CUDA backend was compiled in.
bool compiled();
// True when it was compiled in and a usable device is present; otherwise
// false, with the reason in *why (when given).
bool available(std::string* why = nullptr);

// Marching cubes + KEY-REDUCE on the GPU; the mesh is byte-identical to the
// CPU backend's for the same options (same key order, same arithmetic, the
// same fixed merge order for averaged normals). Supports KeyReduce and
// KeyReduceSort welds, normals none / gradient / average, curvature, scalars
// and several isovalues, and coarsening (options.coarsen: the contour's device
// path, then coarsen_device.hpp's, equal to generate::contour's); throws
// InputError naming what it does not support yet (history, output
// arrays, slabs, ghost planes: src/cuda/contour_limits.hpp) and when no
// device is usable, LimitError past
// its sizes, past options.max_output_bytes (the CPU's check and message) and
// when the device runs out of memory. After a fault that leaves the CUDA
// context unusable, available() is false, saying why.
SurfaceMesh contour(const ImageGrid& grid, const generate::ContourOptions& options,
                    generate::ContourStats* stats = nullptr);

}  // namespace keymesh::cuda
