// The CUDA backend of marching cubes + KEY-REDUCE (see keymesh/cuda/backend.hpp).
//
// The stages mirror the CPU backend and share its per-element functors
// (keymesh/generate/contour/contour_kernels.hpp), compiled here for the device with
// --fmad=false so that every floating-point operation rounds as on the CPU:
//   1. classify: one thread per voxel, its case;
//   2. scan the cases' triangle counts in 64 bits (CUB; the total cannot wrap
//      past 2^32 and is checked against the limits before anything is sized
//      from it), emit the soup of edge keys in voxel order (the CPU's order,
//      so the index map, the triangle list, comes out the same);
//   3. KEY-REDUCE, sort plan: stable radix sort of (key, pair) pairs (CUB) on
//      the significant key bits, heads of equal keys, an inclusive scan: the
//      groups in increasing key order, as the CPU's dense and sort plans give;
//   4. positions and fields once per group, from its key;
//   5. averaged normals: each point sums its triangles' normals in the CPU's
//      fixed order (even slab blocks, then odd; pair order within a block).
// Device memory comes from CUDA's stream-ordered pool (cudaMallocAsync), so
// buffers freed by a stage are reused by the next without new allocations
// (the pool's release threshold is raised so that it keeps them across the
// synchronizations, and for the next contour); the arrays of a mesh handed to
// the caller (contour_device) come from cudaMalloc and go with cudaFree.
// Stage times are the device's: CUDA events around each stage's launches.
#include <cuda_runtime.h>
#include <thrust/iterator/transform_iterator.h>

#include <atomic>
#include <cstring>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "contour_limits.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/cuda/device_contour.hpp"
#include "keymesh/generate/contour/contour_kernels.hpp"
#include "keymesh/generate/contour/marching_cubes_table.hpp"

namespace keymesh::cuda {

namespace {

using generate::EdgeInterpolator;
using generate::GridShape;
using ::keymesh::Vec3f;

// A fault that leaves the context unusable (an illegal address in a kernel,
// say): every later CUDA call of the process fails with it, so available()
// reports it instead of offering the GPU again.
std::mutex g_dead_mutex;
std::atomic<bool> g_dead{false};
std::string g_dead_why;

bool is_sticky(cudaError_t e) {
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

// Every CUDA call and launch goes through KEYMESH_CUDA_CHECK: out of device
// memory is a LimitError that names the CPU backend; any other error an
// InputError with the CUDA error's text and the call's file:line.
void check_at(cudaError_t e, const char* what, const char* file, int line) {
  if (e == cudaSuccess) return;
  const char* from_src = std::strstr(file, "src/cuda/");  // the repository's path, not the build machine's
  const std::string where = std::string(" (") + (from_src ? from_src : file) + ":" + std::to_string(line) + ")";
  const std::string error = std::string(cudaGetErrorName(e)) + ": " + cudaGetErrorString(e);
  if (e == cudaErrorMemoryAllocation) {
    cudaGetLastError();  // not sticky: clear it, the process may go on (on the CPU)
    throw LimitError(std::string("--backend cuda: out of device memory (") + what + where +
                     "); use --backend cpu, or a smaller volume");
  }
  if (is_sticky(e)) {
    std::lock_guard<std::mutex> lock(g_dead_mutex);
    if (!g_dead)
      g_dead_why = std::string("the GPU failed earlier in this process (") + error + ", " + what + where +
                   "); use --backend cpu or a new process";
    g_dead = true;
  }
  throw InputError(std::string("--backend cuda: ") + what + ": " + error + where);
}
#define KEYMESH_CUDA_CHECK(call, what) check_at((call), (what), __FILE__, __LINE__)
// After a launch: its configuration errors now, its faults at the next sync.
#define KEYMESH_CUDA_LAUNCHED(what) check_at(cudaGetLastError(), (what), __FILE__, __LINE__)

// Where a DeviceArray's memory comes from: the stream-ordered pool (freed
// on the stream when the array goes), or cudaMalloc for an array handed to
// the caller (release(): freed by cudaFree when the caller's last copy goes).
enum class Memory { Pool, Handed };

// A device array from the stream-ordered pool, or handed to the caller.
template <class T>
class DeviceArray {
 public:
  DeviceArray() = default;
  DeviceArray(std::size_t n, cudaStream_t s, Memory memory = Memory::Pool) : n_(n), s_(s), memory_(memory) {
    if (!n) return;
    if (memory == Memory::Pool)
      KEYMESH_CUDA_CHECK(cudaMallocAsync(reinterpret_cast<void**>(&p_), n * sizeof(T), s), "allocating device memory");
    else
      KEYMESH_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&p_), n * sizeof(T)),
                         "allocating the mesh's device memory");
  }
  DeviceArray(DeviceArray&& o) noexcept
      : p_(std::exchange(o.p_, nullptr)), n_(o.n_), s_(o.s_), memory_(o.memory_) {}
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  DeviceArray& operator=(DeviceArray&& o) noexcept {
    if (this != &o) {
      free();
      p_ = std::exchange(o.p_, nullptr), n_ = o.n_, s_ = o.s_, memory_ = o.memory_;
    }
    return *this;
  }
  ~DeviceArray() { free(); }
  T* get() const { return p_; }
  std::size_t size() const { return n_; }
  void upload(const T* host, std::size_t n) {
    KEYMESH_CUDA_CHECK(cudaMemcpyAsync(p_, host, n * sizeof(T), cudaMemcpyHostToDevice, s_), "uploading");
  }
  void download(T* host, std::size_t n) const {
    KEYMESH_CUDA_CHECK(cudaMemcpyAsync(host, p_, n * sizeof(T), cudaMemcpyDeviceToHost, s_), "downloading");
  }
  // A Handed array's memory, now the caller's (null when empty).
  DeviceBuffer release() {
    return DeviceBuffer(std::exchange(p_, nullptr), [](void* p) {
      if (p) cudaFree(p);  // errors ignored: at exit the runtime may be gone already
    });
  }

 private:
  void free() {
    if (!p_) return;
    if (memory_ == Memory::Pool) cudaFreeAsync(p_, s_);
    else cudaFree(p_);
    p_ = nullptr;
  }
  T* p_ = nullptr;
  std::size_t n_ = 0;
  cudaStream_t s_ = nullptr;
  Memory memory_ = Memory::Pool;
};

// Stage times from CUDA events recorded on the stream around each stage's
// launches: the device's clock (a host clock around asynchronous launches
// would time the launches, classify's always 0).
class StageTimes {
 public:
  using Stage = double generate::ContourStats::*;
  explicit StageTimes(cudaStream_t s) : s_(s) {}
  StageTimes(const StageTimes&) = delete;
  StageTimes& operator=(const StageTimes&) = delete;
  ~StageTimes() {
    for (const Mark& m : marks_) cudaEventDestroy(m.begin), cudaEventDestroy(m.end);
  }
  void begin(Stage stage) {
    marks_.push_back(Mark{stage, nullptr, nullptr});
    KEYMESH_CUDA_CHECK(cudaEventCreate(&marks_.back().begin), "creating a timing event");
    KEYMESH_CUDA_CHECK(cudaEventCreate(&marks_.back().end), "creating a timing event");
    KEYMESH_CUDA_CHECK(cudaEventRecord(marks_.back().begin, s_), "recording a timing event");
  }
  void end() { KEYMESH_CUDA_CHECK(cudaEventRecord(marks_.back().end, s_), "recording a timing event"); }
  // Adds every stage's seconds to st, once the stream is done.
  void add_to(generate::ContourStats& st) const {
    KEYMESH_CUDA_CHECK(cudaStreamSynchronize(s_), "reading the stage times");
    for (const Mark& m : marks_) {
      float ms = 0;
      KEYMESH_CUDA_CHECK(cudaEventElapsedTime(&ms, m.begin, m.end), "reading a timing event");
      st.*m.stage += ms / 1000.0;
    }
  }

 private:
  struct Mark {
    Stage stage;
    cudaEvent_t begin, end;
  };
  cudaStream_t s_;
  std::vector<Mark> marks_;
};

__constant__ generate::MarchingCubesTable d_table;

constexpr int kThreads = 256;
unsigned grid_for(Id n) { return static_cast<unsigned>((n + kThreads - 1) / kThreads); }

// Stage 1: case of every voxel. mode: 0 compare, 1 none inside, 2 all inside.
template <class T>
__global__ void classify_kernel(const T* samples, GridShape s, T threshold, int mode, std::uint8_t* cases, Id voxels) {
  const Id v = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (v >= voxels) return;
  const Id i = v % (s.nx - 1), r = v / (s.nx - 1), j = r % (s.ny - 1), k = r / (s.ny - 1);
  const Id p0 = i + s.nx * j + s.nxy * k;
  unsigned c = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const Id q = p0 + (corner & 1) + s.nx * ((corner >> 1) & 1) + s.nxy * ((corner >> 2) & 1);
    const bool in = mode == 2 || (mode == 0 && samples[q] >= threshold);
    c |= static_cast<unsigned>(in) << corner;
  }
  cases[v] = static_cast<std::uint8_t>(c);
}

// A voxel's triangle count from its case, 64-bit: the scan over the voxels
// sums in 64 bits, so past 2^32 triangles the total does not wrap.
struct TriangleCountOf {
  __device__ std::uint64_t operator()(std::uint8_t c) const { return d_table.triangle_count[c]; }
};

// The first triangle of every `stride`-th voxel (the CPU's reduce_blocked
// blocks start every 4 voxel slabs), gathered for one download.
__global__ void gather_kernel(const std::uint64_t* offsets, Id stride, std::uint64_t* out, Id n) {
  const Id b = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (b < n) out[b] = offsets[b * stride];
}

// Stage 2: the soup, an edge key per triangle corner, in voxel order.
template <class K>
__global__ void emit_kernel(const std::uint8_t* cases, const std::uint64_t* offsets, GridShape s, K key_offset, K* keys,
                            Id voxels) {
  const Id v = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (v >= voxels) return;
  const unsigned c = cases[v];
  const int corners = 3 * d_table.triangle_count[c];
  if (corners == 0) return;
  const Id i = v % (s.nx - 1), r = v / (s.nx - 1), j = r % (s.ny - 1), k = r / (s.ny - 1);
  const K voxel_key = key_offset + static_cast<K>(3 * (i + s.nx * j + s.nxy * k));
  K* o = keys + 3 * offsets[v];
  for (int n = 0; n < corners; ++n) {
    const auto& ce = d_table.edges[d_table.triangle_edges[c][n]];
    o[n] = voxel_key + static_cast<K>(3 * (ce.dx + ce.dy * s.nx + ce.dz * s.nxy) + ce.axis);
  }
}

__global__ void iota_kernel(std::uint32_t* v, Id n) {
  const Id i = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < n) v[i] = static_cast<std::uint32_t>(i);
}

// Stage 3: 1 where a run of equal sorted keys starts.
template <class K>
__global__ void heads_kernel(const K* sorted, std::uint32_t* heads, Id n) {
  const Id j = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (j < n) heads[j] = (j == 0 || sorted[j] != sorted[j - 1]) ? 1u : 0u;
}

// Group of every sorted position (inclusive scan of heads, minus one): the
// unique keys, each group's first position, and the index map.
template <class K>
__global__ void groups_kernel(const K* sorted, const std::uint32_t* perm, const std::uint32_t* scanned, K* unique_keys,
                              std::uint32_t* group_begin, std::uint32_t* index_map, Id n) {
  const Id j = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (j >= n) return;
  const std::uint32_t g = scanned[j] - 1;
  if (j == 0 || sorted[j] != sorted[j - 1]) {
    unique_keys[g] = sorted[j];
    group_begin[g] = static_cast<std::uint32_t>(j);
  }
  index_map[perm[j]] = g;
}

// Stage 4: position, scalar and gradient normal of every point, from its key.
template <class T, class K>
__global__ void points_kernel(EdgeInterpolator<T> interp, const K* keys, float* xyz, float* scalar, float* normal,
                              Id points) {
  const Id p = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (p >= points) return;
  const auto e = interp.locate(static_cast<std::uint64_t>(keys[p]));
  interp.position(e, xyz + 3 * p);
  if (scalar) scalar[p] = interp.scalar(e);
  if (normal) interp.gradient_normal(e, normal + 3 * p);
}

__global__ void face_kernel(const float* xyz, const std::uint32_t* conn, Vec3f* face, Id triangles) {
  const Id t = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (t < triangles) face[t] = ::keymesh::triangle_normal(xyz, conn, t);
}

// Stage 5: each point sums its triangles' normals over the pairs of even
// blocks, then odd blocks, in pair order: keyreduce::reduce_blocked's order.
__global__ void average_kernel(const std::uint32_t* perm, const std::uint32_t* group_begin, Id pairs, const Vec3f* face,
                               const Id* blocks, Id block_count, float* normal, Id points) {
  const Id g = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (g >= points) return;
  const Id b = group_begin[g], e = g + 1 < points ? group_begin[g + 1] : pairs;
  Vec3f acc{0, 0, 0};
  for (int parity = 0; parity < 2; ++parity)
    for (Id j = b; j < e; ++j) {
      const Id pair = perm[j];
      Id lo = 0, hi = block_count;  // the block holding `pair`: blocks[lo] <= pair < blocks[lo + 1]
      while (hi - lo > 1) {
        const Id mid = (lo + hi) / 2;
        if (blocks[mid] <= pair) lo = mid;
        else hi = mid;
      }
      if ((lo & 1) == parity) acc = ::keymesh::add(acc, face[pair / 3]);
    }
  const Vec3f u = ::keymesh::unit(acc);
  normal[3 * g] = u.x, normal[3 * g + 1] = u.y, normal[3 * g + 2] = u.z;
}

// A mesh contoured over a C-ordered array's reversed axes mirrored back
// (DeviceVolume::mirror_back): x <-> z in points and normals, corners 1 and 2
// of every triangle swapped, as the Python module's mirror_axes on the host.
__global__ void mirror_kernel(float* xyz, float* normal, std::uint32_t* conn, Id points, Id triangles) {
  const Id i = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < points) {
    const float x = xyz[3 * i];
    xyz[3 * i] = xyz[3 * i + 2], xyz[3 * i + 2] = x;
    if (normal) {
      const float nx = normal[3 * i];
      normal[3 * i] = normal[3 * i + 2], normal[3 * i + 2] = nx;
    }
  }
  if (i < triangles) {
    const std::uint32_t b = conn[3 * i + 1];
    conn[3 * i + 1] = conn[3 * i + 2], conn[3 * i + 2] = b;
  }
}

// The grid as the kernels see it (a whole grid: no slab, no host table).
GridShape shape_of(const ImageGrid& grid) {
  GridShape s{};
  s.nx = grid.dims[0], s.ny = grid.dims[1], s.nz = grid.dims[2];
  s.nxy = s.nx * s.ny, s.n = s.nxy * s.nz;
  for (int a = 0; a < 3; ++a) s.origin[a] = grid.origin[a], s.spacing[a] = grid.spacing[a];
  s.stride[0] = 1, s.stride[1] = s.nx, s.stride[2] = s.nxy;
  return s;
}

// Stage 1's arrays, one entry per voxel, reused by every isovalue: its case
// and the exclusive scan of the triangle counts (its first triangle, 64-bit).
struct VoxelCases {
  VoxelCases(Id voxels, cudaStream_t stream)
      : cases(static_cast<std::size_t>(voxels), stream), offsets(static_cast<std::size_t>(voxels), stream) {}
  DeviceArray<std::uint8_t> cases;
  DeviceArray<std::uint64_t> offsets;
};

// The soup as stage 2 leaves it: one part per isovalue, and the first pair of
// every 4 voxel slabs (the CPU's reduce_blocked blocks) across the parts.
template <class K>
struct SoupParts {
  std::vector<std::unique_ptr<DeviceArray<K>>> keys;  // freed by join_parts
  std::vector<Id> size;
  std::vector<Id> blocks;
  Id corners = 0;
};

// After stage 1's scan: the isovalue's triangles (64-bit: the last voxel's
// first triangle plus its count), and the first triangle of every 4th voxel
// slab. Waits for the stream.
struct TriangleOffsets {
  std::uint64_t triangles = 0;
  std::vector<std::uint64_t> slab_first;
};

TriangleOffsets download_offsets(const VoxelCases& v, const GridShape& s, Id voxels,
                                 const generate::MarchingCubesTable& table, cudaStream_t stream) {
  std::uint64_t last_offset = 0;
  std::uint8_t last_case = 0;
  KEYMESH_CUDA_CHECK(cudaMemcpyAsync(&last_offset, v.offsets.get() + voxels - 1, 8, cudaMemcpyDeviceToHost, stream),
                     "downloading the triangle count");
  KEYMESH_CUDA_CHECK(cudaMemcpyAsync(&last_case, v.cases.get() + voxels - 1, 1, cudaMemcpyDeviceToHost, stream),
                     "downloading the triangle count");
  TriangleOffsets out;
  const Id slab_blocks = (s.nz - 1 + 3) / 4;
  out.slab_first.resize(static_cast<std::size_t>(slab_blocks));
  DeviceArray<std::uint64_t> firsts(out.slab_first.size(), stream);
  gather_kernel<<<grid_for(slab_blocks), kThreads, 0, stream>>>(v.offsets.get(), 4 * (s.ny - 1) * (s.nx - 1),
                                                                firsts.get(), slab_blocks);
  KEYMESH_CUDA_LAUNCHED("gathering the slab blocks' first triangles");
  firsts.download(out.slab_first.data(), out.slab_first.size());
  KEYMESH_CUDA_CHECK(cudaStreamSynchronize(stream), "classify");
  out.triangles = last_offset + table.triangle_count[last_case];
  return out;
}

// Stages 1 and 2 for one isovalue: classify the voxels, scan their triangle
// counts (64-bit), and emit this isovalue's part of the soup (keys +
// key_offset), appended to `parts` with its slab blocks; refused (LimitError)
// past the device sort's corners or --max-memory before the part is sized.
template <class K, class T>
void emit_isovalue(const T* samples, const GridShape& s, Id voxels, const generate::ContourOptions& opt, Id iso_index,
                   K key_offset, VoxelCases& v, SoupParts<K>& parts, StageTimes& times, cudaStream_t stream) {
  const generate::InsideTest<T> test(opt.isovalues[static_cast<std::size_t>(iso_index)]);
  times.begin(&generate::ContourStats::classify);
  classify_kernel<T><<<grid_for(voxels), kThreads, 0, stream>>>(
      samples, s, test.threshold, test.all ? 2 : (test.none ? 1 : 0), v.cases.get(), voxels);
  KEYMESH_CUDA_LAUNCHED("classify");
  times.end();
  times.begin(&generate::ContourStats::generate);
  // The scan's storage is freed when this isovalue is done, after its part is allocated.
  const auto counts = thrust::make_transform_iterator(v.cases.get(), TriangleCountOf{});
  std::size_t temp_bytes = 0;
  KEYMESH_CUDA_CHECK(
      cub::DeviceScan::ExclusiveSum(nullptr, temp_bytes, counts, v.offsets.get(), static_cast<int>(voxels), stream),
      "sizing the triangle counts' scan");
  DeviceArray<std::uint8_t> temp(temp_bytes, stream);
  KEYMESH_CUDA_CHECK(
      cub::DeviceScan::ExclusiveSum(temp.get(), temp_bytes, counts, v.offsets.get(), static_cast<int>(voxels), stream),
      "scanning triangle counts");
  const TriangleOffsets counted =
      download_offsets(v, s, voxels, generate::marching_cubes_table(opt.reversed_axes), stream);
  const Id corners = gpu_soup_corners(parts.corners, counted.triangles);
  const Id triangles = (corners - parts.corners) / 3;
  generate::check_contour_output(opt, 0, corners / 3);  // --max-memory, on the triangles alone so far
  for (std::uint64_t first : counted.slab_first) parts.blocks.push_back(parts.corners + 3 * static_cast<Id>(first));
  parts.keys.push_back(std::make_unique<DeviceArray<K>>(static_cast<std::size_t>(3 * triangles), stream));
  DeviceArray<K>* part = parts.keys.back().get();
  parts.size.push_back(3 * triangles);
  if (triangles > 0) {
    emit_kernel<K><<<grid_for(voxels), kThreads, 0, stream>>>(v.cases.get(), v.offsets.get(), s, key_offset,
                                                              part->get(), voxels);
    KEYMESH_CUDA_LAUNCHED("emit");
  }
  times.end();
  parts.corners = corners;
}

// One soup: the parts end to end, then the parts freed.
template <class K>
void join_parts(SoupParts<K>& parts, DeviceArray<K>& soup, cudaStream_t stream) {
  Id at = 0;
  for (std::size_t k = 0; k < parts.keys.size(); ++k) {
    if (parts.size[k])
      KEYMESH_CUDA_CHECK(cudaMemcpyAsync(soup.get() + at, parts.keys[k]->get(), parts.size[k] * sizeof(K),
                                         cudaMemcpyDeviceToDevice, stream),
                         "joining the soup");
    at += parts.size[k];
  }
  parts.keys.clear();
}

// Stage 3a: the pairs (key, pair index) sorted by key, stably, on the keys'
// significant bits: `sorted` the keys, `perm` the pair indices.
template <class K>
void sort_soup(const DeviceArray<K>& soup, K key_range, DeviceArray<std::uint32_t>& pair_in, DeviceArray<K>& sorted,
               DeviceArray<std::uint32_t>& perm, int n, cudaStream_t stream) {
  iota_kernel<<<grid_for(n), kThreads, 0, stream>>>(pair_in.get(), n);
  KEYMESH_CUDA_LAUNCHED("numbering the pairs");
  int end_bit = 0;
  while (end_bit < int(sizeof(K) * 8) && ((key_range - 1) >> end_bit) != 0) ++end_bit;
  std::size_t temp_bytes = 0;
  KEYMESH_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, temp_bytes, soup.get(), sorted.get(), pair_in.get(),
                                                     perm.get(), n, 0, std::max(end_bit, 1), stream),
                     "sizing the soup's sort");
  DeviceArray<std::uint8_t> temp(temp_bytes, stream);
  KEYMESH_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(temp.get(), temp_bytes, soup.get(), sorted.get(), pair_in.get(),
                                                     perm.get(), n, 0, std::max(end_bit, 1), stream),
                     "sorting the soup");
}

// Stage 3b: 1 where a run of equal sorted keys starts, scanned inclusively
// (each position's group + 1); returns the number of groups. Waits for the stream.
template <class K>
Id count_groups(const DeviceArray<K>& sorted, DeviceArray<std::uint32_t>& heads, DeviceArray<std::uint32_t>& scanned,
                int n, cudaStream_t stream) {
  heads_kernel<K><<<grid_for(n), kThreads, 0, stream>>>(sorted.get(), heads.get(), n);
  KEYMESH_CUDA_LAUNCHED("marking group heads");
  {
    std::size_t temp_bytes = 0;
    KEYMESH_CUDA_CHECK(cub::DeviceScan::InclusiveSum(nullptr, temp_bytes, heads.get(), scanned.get(), n, stream),
                       "sizing the group heads' scan");
    DeviceArray<std::uint8_t> temp(temp_bytes, stream);
    KEYMESH_CUDA_CHECK(cub::DeviceScan::InclusiveSum(temp.get(), temp_bytes, heads.get(), scanned.get(), n, stream),
                       "scanning group heads");
  }
  std::uint32_t groups = 0;
  KEYMESH_CUDA_CHECK(cudaMemcpyAsync(&groups, scanned.get() + n - 1, 4, cudaMemcpyDeviceToHost, stream), "downloading");
  KEYMESH_CUDA_CHECK(cudaStreamSynchronize(stream), "KEY-REDUCE");
  return groups;
}

// Stage 5: averaged normals, each point's triangles' face normals summed in
// the CPU's slab-block order and normalised into `normal`. Waits for the stream.
void average_normals(const DeviceArray<float>& xyz, const DeviceArray<std::uint32_t>& index_map,
                     const DeviceArray<std::uint32_t>& perm, const DeviceArray<std::uint32_t>& group_begin,
                     const std::vector<Id>& blocks, int n, Id points, DeviceArray<float>& normal,
                     cudaStream_t stream) {
  const Id triangles = n / 3;
  DeviceArray<Vec3f> face(static_cast<std::size_t>(triangles), stream);
  face_kernel<<<grid_for(triangles), kThreads, 0, stream>>>(xyz.get(), index_map.get(), face.get(), triangles);
  KEYMESH_CUDA_LAUNCHED("face normals");
  DeviceArray<Id> d_blocks(blocks.size(), stream);
  d_blocks.upload(blocks.data(), blocks.size());
  average_kernel<<<grid_for(points), kThreads, 0, stream>>>(perm.get(), group_begin.get(), n, face.get(),
                                                            d_blocks.get(), static_cast<Id>(blocks.size()) - 1,
                                                            normal.get(), points);
  KEYMESH_CUDA_LAUNCHED("averaging normals");
  KEYMESH_CUDA_CHECK(cudaStreamSynchronize(stream), "averaging normals");
}

// The mesh as the stages leave it in device memory: the points' positions
// and fields, the triangles (the index map). The four arrays are the pool's
// for a host mesh, Handed for contour_device.
struct DeviceResult {
  Id points = 0;
  Id corners = 0;
  DeviceArray<float> xyz, scalar, normal;
  DeviceArray<std::uint32_t> index_map;
};

// The device's points, triangles and fields into a host mesh (no points:
// the fields asked for, empty). Waits for the stream.
SurfaceMesh download_mesh(const ImageGrid& grid, const generate::ContourOptions& opt, const DeviceResult& r,
                          cudaStream_t stream) {
  SurfaceMesh mesh;
  mesh.points.resize(static_cast<std::size_t>(3 * r.points));
  mesh.connectivity.resize(static_cast<std::size_t>(r.corners));
  if (r.points) r.xyz.download(mesh.points.data(), mesh.points.size());
  if (r.corners) r.index_map.download(mesh.connectivity.data(), mesh.connectivity.size());
  if (opt.scalars) {
    Field f{grid.name, 1, Array<float>(static_cast<std::size_t>(r.points))};
    if (r.points) r.scalar.download(f.values.data(), f.values.size());
    mesh.point_fields.push_back(std::move(f));
  }
  if (opt.normals != generate::ContourNormals::None) {
    Field f{"Normals", 3, Array<float>(static_cast<std::size_t>(3 * r.points))};
    if (r.points) r.normal.download(f.values.data(), f.values.size());
    mesh.point_fields.push_back(std::move(f));
  }
  KEYMESH_CUDA_CHECK(cudaStreamSynchronize(stream), "downloading the mesh");
  return mesh;
}

// Stage 3: KEY-REDUCE, sort plan, over the joined soup of n corners: the
// index map into r (Handed or pool memory as `out` says), and each point's
// key and first sorted pair; `perm` the pairs in sorted order.
template <class K>
void weld_soup(const DeviceArray<K>& soup, K key_range, int n, const generate::ContourOptions& opt, Memory out,
               DeviceResult& r, DeviceArray<K>& unique_keys, DeviceArray<std::uint32_t>& perm,
               DeviceArray<std::uint32_t>& group_begin, cudaStream_t stream) {
  DeviceArray<std::uint32_t> pair_in(static_cast<std::size_t>(n), stream);
  DeviceArray<K> sorted(static_cast<std::size_t>(n), stream);
  sort_soup(soup, key_range, pair_in, sorted, perm, n, stream);
  DeviceArray<std::uint32_t> heads(static_cast<std::size_t>(n), stream), scanned(static_cast<std::size_t>(n), stream);
  r.points = count_groups(sorted, heads, scanned, n, stream);
  generate::check_contour_output(opt, r.points, n / 3);  // --max-memory, before the mesh is allocated
  unique_keys = DeviceArray<K>(static_cast<std::size_t>(r.points), stream);
  group_begin = DeviceArray<std::uint32_t>(static_cast<std::size_t>(r.points), stream);
  r.index_map = DeviceArray<std::uint32_t>(static_cast<std::size_t>(n), stream, out);
  groups_kernel<K><<<grid_for(n), kThreads, 0, stream>>>(sorted.get(), perm.get(), scanned.get(), unique_keys.get(),
                                                         group_begin.get(), r.index_map.get(), n);
  KEYMESH_CUDA_LAUNCHED("grouping");
}

// The stages in order over device samples. The sort's buffers go when
// weld_soup returns (stream-ordered frees, reused by the next stage's
// allocations); the other arrays live to the end (the pool's high-water mark
// is the report's peak); the mesh's arrays come from `out`.
template <class K, class T>
DeviceResult contour_typed(const ImageGrid& grid, const T* samples, const generate::ContourOptions& opt,
                           generate::ContourStats& st, Memory out, StageTimes& times, cudaStream_t stream) {
  const GridShape s = shape_of(grid);
  const Id voxels = gpu_voxels(s.nx, s.ny, s.nz);
  const Id n_iso = static_cast<Id>(opt.isovalues.size());
  const K keys_per_iso = static_cast<K>(3 * s.n);
  const K key_range = static_cast<K>(n_iso) * keys_per_iso;
  st.key_bits = static_cast<int>(sizeof(K) * 8);
  DeviceArray<double> isovalues(opt.isovalues.size(), stream);
  isovalues.upload(opt.isovalues.data(), opt.isovalues.size());
  KEYMESH_CUDA_CHECK(cudaMemcpyToSymbolAsync(d_table, &generate::marching_cubes_table(opt.reversed_axes),
                                             sizeof(generate::MarchingCubesTable), 0, cudaMemcpyHostToDevice, stream),
                     "uploading the case table");

  // Stages 1 and 2, per isovalue; the soup grows iso after iso, as on the CPU.
  VoxelCases cases(voxels, stream);
  SoupParts<K> parts;
  for (Id iso_index = 0; iso_index < n_iso; ++iso_index)
    emit_isovalue<K, T>(samples, s, voxels, opt, iso_index, static_cast<K>(iso_index) * keys_per_iso, cases, parts,
                        times, stream);
  parts.blocks.push_back(parts.corners);
  st.soup_points = parts.corners;
  times.begin(&generate::ContourStats::generate);
  DeviceArray<K> soup(static_cast<std::size_t>(parts.corners), stream);
  join_parts(parts, soup, stream);
  times.end();
  DeviceResult r;
  r.corners = parts.corners;
  const int n = static_cast<int>(parts.corners);
  if (n == 0) return r;

  times.begin(&generate::ContourStats::weld);
  DeviceArray<K> unique_keys;
  DeviceArray<std::uint32_t> perm(static_cast<std::size_t>(n), stream), group_begin;
  weld_soup(soup, key_range, n, opt, out, r, unique_keys, perm, group_begin, stream);
  times.end();

  // Stages 4 and 5: points and fields.
  times.begin(&generate::ContourStats::fields);
  const EdgeInterpolator<T> interp{samples, s, isovalues.get(), static_cast<Id>(keys_per_iso)};
  const auto points = static_cast<std::size_t>(r.points);
  r.xyz = DeviceArray<float>(3 * points, stream, out);
  r.scalar = DeviceArray<float>(opt.scalars ? points : 0, stream, out);
  r.normal = DeviceArray<float>(opt.normals != generate::ContourNormals::None ? 3 * points : 0, stream, out);
  points_kernel<T, K><<<grid_for(r.points), kThreads, 0, stream>>>(
      interp, unique_keys.get(), r.xyz.get(), opt.scalars ? r.scalar.get() : nullptr,
      opt.normals == generate::ContourNormals::Gradient ? r.normal.get() : nullptr, r.points);
  KEYMESH_CUDA_LAUNCHED("points");
  if (opt.normals == generate::ContourNormals::Average)
    average_normals(r.xyz, r.index_map, perm, group_begin, parts.blocks, n, r.points, r.normal, stream);
  times.end();
  return r;
}

// What every GPU contour sets up and undoes: the device (made current, the
// caller's restored after), a stream, and the device's default memory pool
// with its high-water mark reset (the report's peak) and its release
// threshold raised: at 0, the pool gives its memory back at every
// synchronization and the next stage allocates it anew; raised, a freed
// block is reused by the next stage and the next contour (the pool keeps up
// to its peak; cudaMemPoolTrimTo or the process's end gives it back).
class GpuSession {
 public:
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

// Calls f(K{}, T{}) with T the grid's sample type and K the key width its
// key range needs (32 bits when it fits): the types, as tags.
template <class F>
decltype(auto) visit_key_and_sample(const ImageGrid& grid, const generate::ContourOptions& opt, F&& f) {
  const std::uint64_t key_range = 3ull * static_cast<std::uint64_t>(grid.num_points()) * opt.isovalues.size();
  // visit_scalars only for the type: the pointer it passes is not read.
  return visit_scalars(grid, [&](const auto* type_tag) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(type_tag)>>;
    if (key_range <= std::numeric_limits<std::uint32_t>::max()) return f(std::uint32_t{}, T{});
    return f(std::uint64_t{}, T{});
  });
}

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

// A Handed result as the caller's mesh, mirrored back first when asked.
DeviceMesh hand_out(DeviceResult& r, const ImageGrid& grid, const generate::ContourOptions& opt, bool mirror_back,
                    int device, cudaStream_t stream) {
  const Id triangles = r.corners / 3;
  if (mirror_back && r.corners) {
    mirror_kernel<<<grid_for(std::max(r.points, triangles)), kThreads, 0, stream>>>(
        r.xyz.get(), r.normal.get(), r.index_map.get(), r.points, triangles);
    KEYMESH_CUDA_LAUNCHED("mirroring the mesh back");
  }
  KEYMESH_CUDA_CHECK(cudaStreamSynchronize(stream), "finishing the mesh");
  DeviceMesh m;
  m.device = device;
  m.points = r.points;
  m.triangles = triangles;
  m.xyz = r.xyz.release();
  m.connectivity = r.index_map.release();
  if (opt.scalars) m.point_fields.push_back(DeviceField{grid.name, 1, r.scalar.release()});
  if (opt.normals != generate::ContourNormals::None)
    m.point_fields.push_back(DeviceField{"Normals", 3, r.normal.release()});
  return m;
}

}  // namespace

bool compiled() { return true; }

bool available(std::string* why) {
  if (g_dead) {
    std::lock_guard<std::mutex> lock(g_dead_mutex);
    if (why) *why = g_dead_why;
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
  st = generate::ContourStats{};
  GpuSession session(-1);
  StageTimes times(session.stream());
  SurfaceMesh mesh = visit_key_and_sample(grid, opt, [&](auto key_tag, auto sample_tag) {
    using K = decltype(key_tag);
    using T = decltype(sample_tag);
    // The upload counts in the generate stage, as it did with host clocks.
    times.begin(&generate::ContourStats::generate);
    DeviceArray<T> samples(static_cast<std::size_t>(grid.num_points()), session.stream());
    samples.upload(static_cast<const T*>(grid.data()), samples.size());
    times.end();
    const DeviceResult r = contour_typed<K, T>(grid, samples.get(), opt, st, Memory::Pool, times, session.stream());
    times.begin(&generate::ContourStats::fields);  // the download counts in the fields stage, as it did
    SurfaceMesh m = download_mesh(grid, opt, r, session.stream());
    times.end();
    return m;
  });
  times.add_to(st);
  st.device_peak_bytes = session.peak();
  return mesh;
}

DeviceMesh contour_device(const DeviceVolume& volume, const generate::ContourOptions& opt,
                          generate::ContourStats* stats) {
  check_device_volume(volume, opt);
  std::string why;
  if (!available(&why)) throw InputError("--backend cuda: " + why);
  const int holder = device_of(volume.samples);
  if (volume.device >= 0 && volume.device != holder)
    throw InputError("--backend cuda: the volume's samples lie on device " + std::to_string(holder) +
                     ", not on device " + std::to_string(volume.device) + " as it says");
  generate::ContourStats local;
  generate::ContourStats& st = stats ? *stats : local;
  st = generate::ContourStats{};
  GpuSession session(holder);
  StageTimes times(session.stream());
  wait_for(volume.ready_after, session.stream());
  DeviceMesh mesh = visit_key_and_sample(volume.grid, opt, [&](auto key_tag, auto sample_tag) {
    using K = decltype(key_tag);
    using T = decltype(sample_tag);
    DeviceResult r = contour_typed<K, T>(volume.grid, static_cast<const T*>(volume.samples), opt, st,
                                         Memory::Handed, times, session.stream());
    return hand_out(r, volume.grid, opt, volume.mirror_back, session.device(), session.stream());
  });
  times.add_to(st);
  // The pool's peak and the mesh's own arrays (cudaMalloc), live at the end.
  st.device_peak_bytes = session.peak() + mesh_bytes(mesh);
  return mesh;
}

}  // namespace keymesh::cuda
