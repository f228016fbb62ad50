#pragma once
// Marching cubes + KEY-REDUCE on samples already in device memory (a CuPy or
// PyTorch array's, a buffer of the caller's), the mesh left in device memory:
// no host copy either way. The Python module's backend='cuda' on a CUDA
// tensor calls this (python/src/contour_device.cpp); cuda::contour
// (backend.hpp) is the same stages on host samples and a host mesh. Both run
// the voxel contour's device path (generate/contour/contour_device.hpp:
// contour_arrays_on here, on a view of the samples, the outputs left as
// device arrays), the code ctest runs on the CPU device.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "keymesh/generate/contour/contour.hpp"

namespace keymesh::cuda {

// Device memory handed to the caller: freed (cudaFree) when its last copy
// goes. cudaFree waits for the device's work, so a consumer's kernels still
// reading the buffer on a stream of its own finish first.
using DeviceBuffer = std::shared_ptr<void>;

// A volume whose samples are in device memory.
struct DeviceVolume {
  // dims, origin, spacing, type and name as for a host volume; grid.bytes
  // stays empty and grid.external null (the samples are below).
  ImageGrid grid;
  // grid.num_points() samples of grid.type, x fastest, in the memory of a
  // CUDA device (checked: host memory is refused, never read by a kernel).
  const void* samples = nullptr;
  // The device holding them (DLPack's device_id), or -1: the device the
  // pointer belongs to.
  int device = -1;
  // The stream (a cudaStream_t's value: 1 the legacy default stream, 2 the
  // per-thread one) whose work so far must end before the samples are read:
  // __cuda_array_interface__'s "stream", or 1 after __dlpack__(stream=1).
  // 0: the samples are ready.
  std::uintptr_t ready_after = 0;
  // The grid is a C-ordered array's axes reversed (the Python module's
  // CAsReversedAxes, with options.reversed_axes): the mesh is mirrored back on
  // the device, x <-> z in points and normals and two corners of every
  // triangle swapped, as the module mirrors a host mesh.
  bool mirror_back = false;
};

// A float32 point field in device memory: components per point.
struct DeviceField {
  std::string name;
  int components = 1;
  DeviceBuffer values;
};

// The mesh in device memory: what cuda::contour gives on the host, the same
// bits (empty buffers when there are no points).
struct DeviceMesh {
  int device = 0;
  Id points = 0, triangles = 0;
  DeviceBuffer xyz;                       // float32, 3 per point
  DeviceBuffer connectivity;              // uint32, 3 per triangle
  std::vector<DeviceField> point_fields;  // the scalar (grid.name), then "Normals", as options ask
};

// What contour_device refuses before any device is touched, in every build
// (InputError; host code, tested without a GPU): the options cuda::contour
// refuses (check_gpu_options), no isovalue or a non-finite one, fewer than 2
// points along an axis, null samples, a sample type that is no grid type;
// LimitError past the GPU's voxel count.
void check_device_volume(const DeviceVolume& volume, const generate::ContourOptions& options);

// cuda::contour's stages on volume.samples; InputError when no device is
// usable (or in a build without CUDA), when the samples are not device
// memory or lie on another device than volume.device, and as cuda::contour
// otherwise; LimitError past its sizes and when the device runs out of
// memory. Stage times in *stats are the device's (CUDA events).
DeviceMesh contour_device(const DeviceVolume& volume, const generate::ContourOptions& options,
                          generate::ContourStats* stats = nullptr);

}  // namespace keymesh::cuda
