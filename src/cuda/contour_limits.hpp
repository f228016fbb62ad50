#pragma once
// What the CUDA contour refuses, and the arithmetic that sized the first
// cut's arrays, as host code compiled in every build (with nvcc or without):
// the tests check it on machines without a GPU
// (tests/cuda/contour_limits_test.cpp). src/cuda/contour_cuda.cu calls
// check_gpu_options; the device path it now runs counts in 64 bits and
// checks its sizes with check_contour_output, so gpu_voxels and
// gpu_soup_corners (CUB's former int counts) are no longer called.
#include <cstdint>

#include "keymesh/generate/contour/contour.hpp"

namespace keymesh::cuda {

// Options the GPU path does not implement are refused by name (InputError,
// "--backend cuda: ... (use --backend cpu)") instead of being ignored:
// per-point history, output arrays a caller owns, slabs, and ghost planes (the CPU's own check refuses those outside a slab). Coarsening
// runs on the GPU (contour_coarsened.cuh) but for device-resident samples
// (check_device_volume refuses it).
void check_gpu_options(const generate::ContourOptions& options);

// The voxels of an nx x ny x nz grid; LimitError past 2^31 - 1 (CUB's item
// counts are int).
Id gpu_voxels(Id nx, Id ny, Id nz);

// The soup's corners once `triangles` more are appended to `corners`.
// `triangles` is the 64-bit total of the device's scan (the last voxel's
// offset plus its count), never a 32-bit sum that could wrap past 2^32;
// LimitError past the device sort's 2^31 - 1 corners, before anything is
// sized from it.
Id gpu_soup_corners(Id corners, std::uint64_t triangles);

}  // namespace keymesh::cuda
