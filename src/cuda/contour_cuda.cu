// The CUDA backend of marching cubes + KEY-REDUCE (see keymesh/cuda/backend.hpp
// and keymesh/cuda/device_contour.hpp): the voxel contour's device path
// (keymesh/generate/contour/contour_device.hpp), the code ctest runs bit for
// bit against the CPU on the CPU device, here on the CUDA device
// (keymesh/device/cuda_device.cuh: CUB's scan and radix sort, a grid-stride
// loop for the functors, every CUDA call checked). The functors are compiled
// with --fmad=false so that every floating-point operation rounds as on the CPU.
//
// The plan is the one --weld names (generate::device_plan_for: keyreduce ->
// the structured count/scan/write plan, keyreduce-sort -> the sort plan,
// vertexweld -> VERTEX-WELD; with --coarsen, contour_coarsened.cuh's: the
// contour's device arrays coarsened on the device); one code path, two entries:
//   contour         host samples (uploaded), the mesh brought to the host;
//   contour_device  samples already in device memory (read where they lie:
//                   contour_arrays_on's view), the mesh left on the device in
//                   memory handed to the caller (cudaMalloc, freed by cudaFree
//                   when its last copy goes), mirrored back there when asked.
// This file holds what only the contour needs on the GPU (gpu_session.cuh has
// the device, stream and memory pool every GPU run sets up): the stage times
// (CUDA events, device::CudaStageEvents), whether a usable device is present,
// and the checks of a caller's device pointer and stream.
#include <cuda_runtime.h>

#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include "contour_coarsened.cuh"
#include "contour_limits.hpp"
#include "gpu_session.cuh"
#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/cuda/device_contour.hpp"
#include "keymesh/device/cuda_device.cuh"
#include "keymesh/generate/contour/contour_device.hpp"
#include "keymesh/generate/contour/contour_device_plans.hpp"

namespace keymesh::cuda {

namespace {

// The bytes of a mesh's device arrays.
std::uint64_t mesh_bytes(const DeviceMesh& m) {
  std::uint64_t floats_per_point = 3;
  for (const DeviceField& f : m.point_fields) floats_per_point += static_cast<std::uint64_t>(f.components);
  return static_cast<std::uint64_t>(m.points) * floats_per_point * 4 + static_cast<std::uint64_t>(m.triangles) * 12;
}

// The device of a pointer to device memory; InputError for host memory or a
// pointer CUDA does not know (never handed to a kernel).
int device_of(const void* p) {
  cudaPointerAttributes a{};
  const cudaError_t e = cudaPointerGetAttributes(&a, p);
  if (e != cudaSuccess || (a.type != cudaMemoryTypeDevice && a.type != cudaMemoryTypeManaged)) {
    cudaGetLastError();  // clear a non-sticky error of the query
    throw InputError("--backend cuda: the volume's samples are not in device memory (a host pointer, or memory "
                     "CUDA does not know); pass a CUDA array, or a host array with backend cpu");
  }
  return a.device;
}

// The stream waits for the work so far on `ready_after` (a cudaStream_t's
// value; 0: nothing to wait for).
void wait_for(std::uintptr_t ready_after, cudaStream_t stream) {
  if (!ready_after) return;
  cudaEvent_t ready;
  KEYMESH_CUDA_CHECK(cudaEventCreateWithFlags(&ready, cudaEventDisableTiming), "creating an event");
  const cudaError_t recorded = cudaEventRecord(ready, reinterpret_cast<cudaStream_t>(ready_after));
  const cudaError_t waited = recorded == cudaSuccess ? cudaStreamWaitEvent(stream, ready, 0) : recorded;
  cudaEventDestroy(ready);
  KEYMESH_CUDA_CHECK(waited, "waiting for the volume's stream");
}

using Arrays = generate::device_contour::ContourArrays<device::CudaDevice>;

// The device path's arrays (Handed memory) as the caller's mesh: fields in
// cuda::contour's order, present when asked for (empty buffers without points).
DeviceMesh hand_out(Arrays& a, const ImageGrid& grid, const generate::ContourOptions& opt, int device) {
  DeviceMesh m;
  m.device = device;
  m.points = a.points;
  m.triangles = a.triangles;
  m.xyz = a.xyz.release();
  m.connectivity = a.connectivity.release();
  if (opt.scalars) m.point_fields.push_back(DeviceField{grid.name, 1, a.fields.scalar.release()});
  if (opt.normals == generate::ContourNormals::Gradient)
    m.point_fields.push_back(DeviceField{"Normals", 3, a.fields.gradient_normal.release()});
  if (opt.normals == generate::ContourNormals::Average)
    m.point_fields.push_back(DeviceField{"Normals", 3, a.fields.averaged_normal.release()});
  return m;
}

}  // namespace

bool compiled() { return true; }

bool available(std::string* why) {
  device::CudaHealth& health = device::cuda_health();
  if (health.dead) {
    std::lock_guard<std::mutex> lock(health.mutex);
    if (why) *why = health.why;
    return false;
  }
  int devices = 0;
  const cudaError_t e = cudaGetDeviceCount(&devices);
  if (e != cudaSuccess || devices == 0) {
    if (why) *why = e != cudaSuccess ? std::string("no usable CUDA device: ") + cudaGetErrorString(e)
                                     : std::string("no CUDA device present");
    cudaGetLastError();  // clear the sticky error
    return false;
  }
  return true;
}

SurfaceMesh contour(const ImageGrid& grid, const generate::ContourOptions& opt, generate::ContourStats* stats) {
  check_gpu_options(opt);
  require_gpu();
  generate::ContourStats local;
  generate::ContourStats& st = stats ? *stats : local;
  GpuSession session(-1);
  device::CudaStageEvents times(session.stream());
  const device::CudaDevice d{session.stream(), &times, device::CudaMemory::Pool};
  // The upload counts in generate, the download in fields (coarsen: the coarsening and the split).
  SurfaceMesh mesh = opt.coarsen ? contour_coarsened_on_gpu(d, grid, opt, &st)
                                 : generate::contour_plan_on(d, grid, opt, generate::device_plan_for(opt.weld), &st);
  times.add_times();
  st.device_peak_bytes = session.peak();
  return mesh;
}

DeviceMesh contour_device(const DeviceVolume& volume, const generate::ContourOptions& opt,
                          generate::ContourStats* stats) {
  check_device_volume(volume, opt);
  require_gpu();
  const int holder = device_of(volume.samples);
  if (volume.device >= 0 && volume.device != holder)
    throw InputError("--backend cuda: the volume's samples lie on device " + std::to_string(holder) +
                     ", not on device " + std::to_string(volume.device) + " as it says");
  generate::ContourStats local;
  generate::ContourStats& st = stats ? *stats : local;
  GpuSession session(holder);
  device::CudaStageEvents times(session.stream());
  wait_for(volume.ready_after, session.stream());
  const device::CudaDevice d{session.stream(), &times, device::CudaMemory::Handed};
  Arrays arrays = generate::contour_plan_arrays_on(d, volume.grid, volume.samples, opt,
                                                   generate::device_plan_for(opt.weld), &st);
  if (volume.mirror_back) {
    const auto mark = d.begin_stage(&st.fields);
    generate::mirror_back(d, arrays);
    d.end_stage(mark);
  }
  times.add_times();  // waits for the stream: the mesh is complete when handed out
  DeviceMesh mesh = hand_out(arrays, volume.grid, opt, session.device());
  // The pool's peak and the mesh's own arrays (cudaMalloc), live at the end.
  st.device_peak_bytes = session.peak() + mesh_bytes(mesh);
  return mesh;
}

}  // namespace keymesh::cuda
