#pragma once
// What every GPU run of a generator sets up and undoes (nvcc only, src/cuda/*.cu):
// the device (made current, the caller's restored after), a stream, and the
// device's default memory pool with its high-water mark reset (the report's
// peak) and its release threshold raised. At 0 the pool gives its memory back
// at every synchronization and the next stage allocates it anew; raised, a
// freed block is reused by the next stage and the next run (the pool keeps up
// to its peak; cudaMemPoolTrimTo or the process's end gives it back).
#include <cuda_runtime.h>

#include <cstdint>
#include <limits>
#include <utility>

#include "keymesh/device/cuda_device.cuh"
#include "unavailable.hpp"

namespace keymesh::cuda {

#define KEYMESH_CUDA_CHECK(call, what) KEYMESH_DEVICE_CUDA_CHECK(call, what)

class GpuSession {
 public:
  // device < 0: the current device.
  explicit GpuSession(int device) {
    KEYMESH_CUDA_CHECK(cudaGetDevice(&previous_), "querying the device");
    if (device >= 0 && device != previous_) KEYMESH_CUDA_CHECK(cudaSetDevice(device), "selecting the device");
    KEYMESH_CUDA_CHECK(cudaGetDevice(&device_), "querying the device");
    KEYMESH_CUDA_CHECK(cudaStreamCreate(&stream_), "creating a stream");
    KEYMESH_CUDA_CHECK(cudaDeviceGetDefaultMemPool(&pool_, device_), "querying the memory pool");
    unsigned long long keep = std::numeric_limits<unsigned long long>::max();  // cuuint64_t (passed as void*)
    KEYMESH_CUDA_CHECK(cudaMemPoolSetAttribute(pool_, cudaMemPoolAttrReleaseThreshold, &keep),
                       "raising the pool's release threshold");
    unsigned long long high = 0;  // only resetting to zero is allowed
    KEYMESH_CUDA_CHECK(cudaMemPoolSetAttribute(pool_, cudaMemPoolAttrUsedMemHigh, &high),
                       "resetting the pool's high-water mark");
  }
  GpuSession(const GpuSession&) = delete;
  GpuSession& operator=(const GpuSession&) = delete;
  ~GpuSession() {
    if (stream_) cudaStreamDestroy(stream_);
    if (device_ != previous_) cudaSetDevice(previous_);
  }
  cudaStream_t stream() const { return stream_; }
  int device() const { return device_; }
  // The pool's high-water mark since the session began, in bytes.
  std::uint64_t peak() const {
    unsigned long long high = 0;
    KEYMESH_CUDA_CHECK(cudaMemPoolGetAttribute(pool_, cudaMemPoolAttrUsedMemHigh, &high),
                       "reading the pool's high-water mark");
    return static_cast<std::uint64_t>(high);
  }

 private:
  int previous_ = 0, device_ = 0;
  cudaStream_t stream_ = nullptr;
  cudaMemPool_t pool_ = nullptr;
};

// run(d) on the current device's own stream, its arrays from the pool: the
// device path of a generator whose input and output are host data (every
// to_host synchronizes, so the result is complete on return). Refused by
// name (InputError naming --backend cpu) when no usable device is present;
// out of device memory is a LimitError naming --backend cpu (cuda_device.cuh).
template <class Run>
auto run_on_gpu(Run&& run) {
  require_gpu();
  GpuSession session(-1);
  const device::CudaDevice d{session.stream(), nullptr, device::CudaMemory::Pool};
  auto result = std::forward<Run>(run)(d);
  d.synchronize();  // the pool's frees of the run's arrays, queued on the stream, reached
  return result;
}

}  // namespace keymesh::cuda
