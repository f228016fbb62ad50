#pragma once
// The CUDA device of the device layer (keymesh/device/algorithms.hpp says what
// a device provides), for .cu files only (nvcc): arrays from CUDA's
// stream-ordered pool, the parallel loop a grid-stride kernel, the scan and
// the radix sort CUB's (64-bit item counts; the scan sums in the output's
// type, never in the input's). Every CUDA call is checked: out of device
// memory is a LimitError naming --backend cpu; a fault that leaves the
// context unusable marks it dead (cuda_context_failed) so that the backend
// stops offering the GPU; any other error an InputError naming the call.
//
// Unverified without a GPU: this file is the launch glue. The functors it
// launches are the ones ctest runs through the CPU device.
#include <cuda_runtime.h>
#include <thrust/iterator/transform_iterator.h>

#include <atomic>
#include <cstring>
#include <memory>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/array.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/core/types.hpp"

namespace keymesh::device {

// Why the CUDA context is unusable ("" while it is not): set by the first
// sticky fault of the process (every later CUDA call fails with it).
struct CudaHealth {
  std::mutex mutex;
  std::atomic<bool> dead{false};
  std::string why;
};
inline CudaHealth& cuda_health() {
  static CudaHealth h;
  return h;
}

inline bool cuda_error_is_sticky(cudaError_t e) {
  switch (e) {
    case cudaErrorIllegalAddress:
    case cudaErrorLaunchFailure:
    case cudaErrorHardwareStackError:
    case cudaErrorIllegalInstruction:
    case cudaErrorMisalignedAddress:
    case cudaErrorInvalidAddressSpace:
    case cudaErrorInvalidPc:
    case cudaErrorAssert:
    case cudaErrorECCUncorrectable:
    case cudaErrorLaunchTimeout:
    case cudaErrorContextIsDestroyed:
    case cudaErrorUnknown:
      return true;
    default:
      return false;
  }
}

inline void cuda_check_at(cudaError_t e, const char* what, const char* file, int line) {
  if (e == cudaSuccess) return;
  const char* from_repo = std::strstr(file, "include/keymesh/");  // the repository's path, not the build machine's
  if (!from_repo) from_repo = std::strstr(file, "src/cuda/");
  const std::string where = std::string(" (") + (from_repo ? from_repo : file) + ":" + std::to_string(line) + ")";
  const std::string error = std::string(cudaGetErrorName(e)) + ": " + cudaGetErrorString(e);
  if (e == cudaErrorMemoryAllocation) {
    cudaGetLastError();  // not sticky: the process may go on, on the CPU
    throw LimitError(std::string("--backend cuda: out of device memory (") + what + where +
                     "); use --backend cpu, or a smaller input");
  }
  if (cuda_error_is_sticky(e)) {
    CudaHealth& h = cuda_health();
    std::lock_guard<std::mutex> lock(h.mutex);
    if (!h.dead)
      h.why = std::string("the GPU failed earlier in this process (") + error + ", " + what + where +
              "); use --backend cpu or a new process";
    h.dead = true;
  }
  throw InputError(std::string("--backend cuda: ") + what + ": " + error + where);
}
#define KEYMESH_DEVICE_CUDA_CHECK(call, what) ::keymesh::device::cuda_check_at((call), (what), __FILE__, __LINE__)

// Where a CudaArray's memory comes from: the stream-ordered pool (freed on
// its stream when the array goes), or cudaMalloc for an array handed to the
// caller (release(): freed by cudaFree when the caller's last copy goes;
// cudaFree waits for the device's work, so a consumer's kernels reading it
// on a stream of their own finish first).
enum class CudaMemory { Pool, Handed };

// Device memory of n elements.
template <class T>
class CudaArray {
 public:
  CudaArray() = default;
  CudaArray(Id n, cudaStream_t s, CudaMemory memory = CudaMemory::Pool) : n_(n), s_(s), memory_(memory) {
    if (n <= 0) return;
    const std::size_t bytes = static_cast<std::size_t>(n) * sizeof(T);
    if (memory == CudaMemory::Pool)
      KEYMESH_DEVICE_CUDA_CHECK(cudaMallocAsync(reinterpret_cast<void**>(&p_), bytes, s), "allocating device memory");
    else
      KEYMESH_DEVICE_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&p_), bytes), "allocating the mesh's device memory");
  }
  CudaArray(CudaArray&& o) noexcept { swap(o); }
  CudaArray& operator=(CudaArray&& o) noexcept {
    CudaArray(std::move(o)).swap(*this);
    return *this;
  }
  CudaArray(const CudaArray&) = delete;
  CudaArray& operator=(const CudaArray&) = delete;
  ~CudaArray() {
    if (!p_) return;
    if (memory_ == CudaMemory::Pool) cudaFreeAsync(p_, s_);
    else cudaFree(p_);
  }
  T* data() const { return p_; }
  std::size_t size() const { return static_cast<std::size_t>(n_); }
  // The memory, handed to the caller (Handed arrays only: pool memory is
  // freed on a stream the caller does not know); empty when n is 0.
  std::shared_ptr<void> release() {
    if (memory_ != CudaMemory::Handed) throw std::logic_error("CudaArray::release: pool memory is not handed out");
    void* p = std::exchange(p_, nullptr);
    n_ = 0;
    if (!p) return {};
    return std::shared_ptr<void>(p, [](void* q) { cudaFree(q); });
  }

 private:
  void swap(CudaArray& o) noexcept {
    std::swap(p_, o.p_);
    std::swap(n_, o.n_);
    std::swap(s_, o.s_);
    std::swap(memory_, o.memory_);
  }
  T* p_ = nullptr;
  Id n_ = 0;
  cudaStream_t s_ = nullptr;
  CudaMemory memory_ = CudaMemory::Pool;
};

// Stage times from CUDA events recorded on the stream around each stage's
// launches: the device's clock (a host clock around asynchronous launches
// times the launches: classify's was always 0). add_to waits for the stream
// (an end event not yet reached reads cudaErrorNotReady).
class CudaStageEvents {
 public:
  explicit CudaStageEvents(cudaStream_t s) : s_(s) {}
  CudaStageEvents(const CudaStageEvents&) = delete;
  CudaStageEvents& operator=(const CudaStageEvents&) = delete;
  ~CudaStageEvents() {
    for (const Mark& m : marks_) cudaEventDestroy(m.begin), cudaEventDestroy(m.end);
  }
  std::size_t begin(double* seconds) {
    marks_.push_back(Mark{seconds, nullptr, nullptr});
    KEYMESH_DEVICE_CUDA_CHECK(cudaEventCreate(&marks_.back().begin), "creating a timing event");
    KEYMESH_DEVICE_CUDA_CHECK(cudaEventCreate(&marks_.back().end), "creating a timing event");
    KEYMESH_DEVICE_CUDA_CHECK(cudaEventRecord(marks_.back().begin, s_), "recording a timing event");
    return marks_.size() - 1;
  }
  void end(std::size_t mark) {
    KEYMESH_DEVICE_CUDA_CHECK(cudaEventRecord(marks_[mark].end, s_), "recording a timing event");
  }
  // Adds every stage's seconds where its begin() said, once the stream is done.
  void add_times() const {
    KEYMESH_DEVICE_CUDA_CHECK(cudaStreamSynchronize(s_), "reading the stage times");
    for (const Mark& m : marks_) {
      float ms = 0;
      KEYMESH_DEVICE_CUDA_CHECK(cudaEventElapsedTime(&ms, m.begin, m.end), "reading a timing event");
      *m.seconds += ms / 1000.0;
    }
  }

 private:
  struct Mark {
    double* seconds;
    cudaEvent_t begin, end;
  };
  cudaStream_t s_;
  std::vector<Mark> marks_;
};

namespace cuda_kernels {

template <class F>
__global__ void for_each_kernel(F f, Id n) {
  const Id stride = static_cast<Id>(gridDim.x) * blockDim.x;
  for (Id i = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x; i < n; i += stride) f(i);
}

template <class U>
struct CastTo {
  template <class T>
  __host__ __device__ U operator()(T v) const {
    return static_cast<U>(v);
  }
};

}  // namespace cuda_kernels

struct CudaDevice {
  static constexpr const char* kName = "cuda";
  static constexpr bool kHostMemory = false;
  static constexpr int kThreads = 256;

  cudaStream_t stream = nullptr;
  // Where the stage times go (null: not timed; the caller reads them with
  // add_times once the work is done).
  CudaStageEvents* stage_events = nullptr;
  // Where a generator's outputs go: the pool (brought to the host), or
  // Handed memory for a mesh left on the device (cuda::contour_device).
  CudaMemory outputs = CudaMemory::Pool;

  template <class T>
  using Array = CudaArray<T>;

  template <class T>
  Array<T> allocate(Id n) const {
    return Array<T>(n, stream);
  }
  template <class T>
  Array<T> allocate_output(Id n) const {
    return Array<T>(n, stream, outputs);
  }
  template <class T>
  Array<T> upload(const T* host, Id n) const {
    Array<T> a(n, stream);
    if (n > 0)
      KEYMESH_DEVICE_CUDA_CHECK(cudaMemcpyAsync(a.data(), host, static_cast<std::size_t>(n) * sizeof(T),
                                                cudaMemcpyHostToDevice, stream),
                                "uploading");
    return a;
  }
  // Waits for the stream: the host copy is complete on return.
  template <class T>
  void download(const T* data, Id n, T* host) const {
    if (n > 0)
      KEYMESH_DEVICE_CUDA_CHECK(cudaMemcpyAsync(host, data, static_cast<std::size_t>(n) * sizeof(T),
                                                cudaMemcpyDeviceToHost, stream),
                                "downloading");
    synchronize();
  }
  template <class T>
  keymesh::Array<T> to_host(Array<T>&& a) const {
    keymesh::Array<T> host(a.size());
    download(a.data(), static_cast<Id>(a.size()), host.data());
    return host;
  }
  template <class T>
  T read(const T* element) const {
    T v{};
    download(element, 1, &v);
    return v;
  }

  template <class F>
  void for_each(Id n, const F& f) const {
    if (n <= 0) return;
    const Id wanted = (n + kThreads - 1) / kThreads;
    const unsigned blocks = static_cast<unsigned>(wanted < (Id{1} << 30) ? wanted : (Id{1} << 30));
    cuda_kernels::for_each_kernel<F><<<blocks, kThreads, 0, stream>>>(f, n);
    KEYMESH_DEVICE_CUDA_CHECK(cudaGetLastError(), "launching a kernel");
  }

  template <class T, class U>
  U exclusive_scan(const T* in, U* out, Id n) const {
    if (n <= 0) return U{};
    // The last input, read before the scan (out may alias in).
    const T last_in = read(in + n - 1);
    const auto summed = thrust::make_transform_iterator(in, cuda_kernels::CastTo<U>{});
    std::size_t bytes = 0;
    KEYMESH_DEVICE_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(nullptr, bytes, summed, out, n, stream), "sizing a scan");
    Array<unsigned char> temp(static_cast<Id>(bytes), stream);
    KEYMESH_DEVICE_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(temp.data(), bytes, summed, out, n, stream), "scanning");
    return static_cast<U>(read(out + n - 1) + static_cast<U>(last_in));
  }

  template <class K, class V>
  void sort_pairs(K* keys, V* values, Id n, int significant_bits) const {
    if (n <= 1 || significant_bits <= 0) return;
    const int end_bit = significant_bits < int(sizeof(K) * 8) ? significant_bits : int(sizeof(K) * 8);
    Array<K> keys_out(n, stream);
    Array<V> values_out(n, stream);
    cub::DoubleBuffer<K> k(keys, keys_out.data());
    cub::DoubleBuffer<V> v(values, values_out.data());
    std::size_t bytes = 0;
    KEYMESH_DEVICE_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, bytes, k, v, n, 0, end_bit, stream),
                              "sizing a sort");
    Array<unsigned char> temp(static_cast<Id>(bytes), stream);
    KEYMESH_DEVICE_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(temp.data(), bytes, k, v, n, 0, end_bit, stream),
                              "sorting");
    if (k.Current() != keys)
      KEYMESH_DEVICE_CUDA_CHECK(cudaMemcpyAsync(keys, k.Current(), static_cast<std::size_t>(n) * sizeof(K),
                                                cudaMemcpyDeviceToDevice, stream),
                                "copying sorted keys");
    if (v.Current() != values)
      KEYMESH_DEVICE_CUDA_CHECK(cudaMemcpyAsync(values, v.Current(), static_cast<std::size_t>(n) * sizeof(V),
                                                cudaMemcpyDeviceToDevice, stream),
                                "copying sorted values");
  }

  void synchronize() const { KEYMESH_DEVICE_CUDA_CHECK(cudaStreamSynchronize(stream), "waiting for the GPU"); }

  using StageMark = std::size_t;
  static constexpr StageMark kUntimed = ~std::size_t{0};
  StageMark begin_stage(double* seconds) const { return stage_events ? stage_events->begin(seconds) : kUntimed; }
  void end_stage(StageMark m) const {
    if (m != kUntimed) stage_events->end(m);
  }
};

}  // namespace keymesh::device
