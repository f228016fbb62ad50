// The CUDA backend of marching cubes + KEY-REDUCE (see keymesh/cuda/backend.hpp):
// the voxel contour's device path (keymesh/generate/contour/contour_device.hpp),
// the code ctest runs bit for bit against the CPU on the CPU device, here on
// the CUDA device (keymesh/device/cuda_device.cuh: CUB's scan and radix sort,
// a grid-stride loop for the functors). The functors are compiled with
// --fmad=false so that every floating-point operation rounds as on the CPU.
//
// This file holds what only the GPU needs: the stream, the memory pool's
// high-water mark for the report, and whether a usable device is present.
// Device memory comes from CUDA's stream-ordered pool (cudaMallocAsync), so
// buffers freed by a stage are reused by the next without new allocations.
#include <cuda_runtime.h>

#include <limits>
#include <string>

#include "contour_limits.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/device/cuda_device.cuh"
#include "keymesh/generate/contour/contour_device.hpp"

namespace keymesh::cuda {

namespace {

#define KEYMESH_CUDA_CHECK(call, what) KEYMESH_DEVICE_CUDA_CHECK(call, what)

struct StreamGuard {
  cudaStream_t s = nullptr;
  ~StreamGuard() {
    if (s) cudaStreamDestroy(s);
  }
};

// The default pool of the current device, its high-water mark reset (only
// resetting to zero is allowed).
cudaMemPool_t reset_pool_peak() {
  int device = 0;
  KEYMESH_CUDA_CHECK(cudaGetDevice(&device), "querying the device");
  cudaMemPool_t pool;
  KEYMESH_CUDA_CHECK(cudaDeviceGetDefaultMemPool(&pool, device), "querying the memory pool");
  unsigned long long high = 0;  // cuuint64_t (the attribute is passed as void*)
  KEYMESH_CUDA_CHECK(cudaMemPoolSetAttribute(pool, cudaMemPoolAttrUsedMemHigh, &high),
                     "resetting the pool's high-water mark");
  return pool;
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
  std::string why;
  if (!available(&why)) throw InputError("--backend cuda: " + why);
  generate::ContourStats local;
  generate::ContourStats& st = stats ? *stats : local;
  StreamGuard guard;
  KEYMESH_CUDA_CHECK(cudaStreamCreate(&guard.s), "creating a stream");
  cudaMemPool_t pool = reset_pool_peak();
  SurfaceMesh mesh = generate::contour_on(device::CudaDevice{guard.s}, grid, opt, &st);
  KEYMESH_CUDA_CHECK(cudaStreamSynchronize(guard.s), "finishing the contour");
  unsigned long long high = 0;
  KEYMESH_CUDA_CHECK(cudaMemPoolGetAttribute(pool, cudaMemPoolAttrUsedMemHigh, &high),
                     "reading the pool's high-water mark");
  st.device_peak_bytes = static_cast<std::uint64_t>(high);
  return mesh;
}

}  // namespace keymesh::cuda
