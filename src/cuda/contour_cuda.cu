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
// buffers freed by a stage are reused by the next without new allocations.
#include <cuda_runtime.h>
#include <thrust/iterator/transform_iterator.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <type_traits>
#include <vector>

#include "contour_limits.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/generate/contour/contour_kernels.hpp"
#include "keymesh/generate/contour/marching_cubes_table.hpp"

namespace keymesh::cuda {

namespace {

using generate::EdgeInterpolator;
using generate::GridShape;
using ::keymesh::Vec3f;

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

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

// A device array from the stream-ordered pool.
template <class T>
class DeviceArray {
 public:
  DeviceArray(std::size_t n, cudaStream_t s) : n_(n), s_(s) {
    if (n)
      KEYMESH_CUDA_CHECK(cudaMallocAsync(reinterpret_cast<void**>(&p_), n * sizeof(T), s), "allocating device memory");
  }
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  ~DeviceArray() {
    if (p_) cudaFreeAsync(p_, s_);
  }
  T* get() const { return p_; }
  std::size_t size() const { return n_; }
  void upload(const T* host, std::size_t n) {
    KEYMESH_CUDA_CHECK(cudaMemcpyAsync(p_, host, n * sizeof(T), cudaMemcpyHostToDevice, s_), "uploading");
  }
  void download(T* host, std::size_t n) const {
    KEYMESH_CUDA_CHECK(cudaMemcpyAsync(host, p_, n * sizeof(T), cudaMemcpyDeviceToHost, s_), "downloading");
  }

 private:
  T* p_ = nullptr;
  std::size_t n_;
  cudaStream_t s_;
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
                   K key_offset, VoxelCases& v, SoupParts<K>& parts, cudaStream_t stream) {
  const generate::InsideTest<T> test(opt.isovalues[static_cast<std::size_t>(iso_index)]);
  classify_kernel<T><<<grid_for(voxels), kThreads, 0, stream>>>(
      samples, s, test.threshold, test.all ? 2 : (test.none ? 1 : 0), v.cases.get(), voxels);
  KEYMESH_CUDA_LAUNCHED("classify");
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

// The mesh of an empty soup: no points, the fields asked for, empty.
SurfaceMesh empty_mesh(const ImageGrid& grid, const generate::ContourOptions& opt) {
  SurfaceMesh mesh;
  if (opt.scalars) mesh.point_fields.push_back(Field{grid.name, 1, {}});
  if (opt.normals != generate::ContourNormals::None) mesh.point_fields.push_back(Field{"Normals", 3, {}});
  return mesh;
}

// The device's points, triangles (the index map) and fields into a mesh.
// Waits for the stream.
SurfaceMesh download_mesh(const ImageGrid& grid, const generate::ContourOptions& opt, Id points, int n,
                          const DeviceArray<float>& xyz, const DeviceArray<std::uint32_t>& index_map,
                          const DeviceArray<float>& scalar, const DeviceArray<float>& normal, cudaStream_t stream) {
  SurfaceMesh mesh;
  mesh.points.resize(static_cast<std::size_t>(3 * points));
  mesh.connectivity.resize(static_cast<std::size_t>(n));
  xyz.download(mesh.points.data(), mesh.points.size());
  index_map.download(mesh.connectivity.data(), mesh.connectivity.size());
  if (opt.scalars) {
    Field f{grid.name, 1, Array<float>(static_cast<std::size_t>(points))};
    scalar.download(f.values.data(), f.values.size());
    mesh.point_fields.push_back(std::move(f));
  }
  if (opt.normals != generate::ContourNormals::None) {
    Field f{"Normals", 3, Array<float>(static_cast<std::size_t>(3 * points))};
    normal.download(f.values.data(), f.values.size());
    mesh.point_fields.push_back(std::move(f));
  }
  KEYMESH_CUDA_CHECK(cudaStreamSynchronize(stream), "downloading the mesh");
  return mesh;
}

// The stages in order. Every device array lives to the end, as the stages
// allocate them (the pool's high-water mark is the report's peak).
template <class K, class T>
SurfaceMesh contour_typed(const ImageGrid& grid, const T* host_samples, const generate::ContourOptions& opt,
                          generate::ContourStats& st, cudaStream_t stream) {
  const GridShape s = shape_of(grid);
  const Id voxels = gpu_voxels(s.nx, s.ny, s.nz);
  const Id n_iso = static_cast<Id>(opt.isovalues.size());
  const K keys_per_iso = static_cast<K>(3 * s.n);
  const K key_range = static_cast<K>(n_iso) * keys_per_iso;
  st.key_bits = static_cast<int>(sizeof(K) * 8);

  auto t0 = Clock::now();
  DeviceArray<T> samples(static_cast<std::size_t>(s.n), stream);
  samples.upload(host_samples, static_cast<std::size_t>(s.n));
  DeviceArray<double> isovalues(opt.isovalues.size(), stream);
  isovalues.upload(opt.isovalues.data(), opt.isovalues.size());
  KEYMESH_CUDA_CHECK(cudaMemcpyToSymbolAsync(d_table, &generate::marching_cubes_table(opt.reversed_axes),
                                             sizeof(generate::MarchingCubesTable), 0, cudaMemcpyHostToDevice, stream),
                     "uploading the case table");

  // Stages 1 and 2, per isovalue; the soup grows iso after iso, as on the CPU.
  VoxelCases cases(voxels, stream);
  SoupParts<K> parts;
  for (Id iso_index = 0; iso_index < n_iso; ++iso_index)
    emit_isovalue<K, T>(samples.get(), s, voxels, opt, iso_index, static_cast<K>(iso_index) * keys_per_iso, cases,
                        parts, stream);
  parts.blocks.push_back(parts.corners);
  st.soup_points = parts.corners;
  DeviceArray<K> soup(static_cast<std::size_t>(parts.corners), stream);
  join_parts(parts, soup, stream);
  KEYMESH_CUDA_CHECK(cudaStreamSynchronize(stream), "generate");
  st.generate += seconds_since(t0);

  // Stage 3: KEY-REDUCE, sort plan.
  t0 = Clock::now();
  const int n = static_cast<int>(parts.corners);
  if (n == 0) return empty_mesh(grid, opt);
  DeviceArray<std::uint32_t> pair_in(static_cast<std::size_t>(n), stream), perm(static_cast<std::size_t>(n), stream);
  DeviceArray<K> sorted(static_cast<std::size_t>(n), stream);
  sort_soup(soup, key_range, pair_in, sorted, perm, n, stream);
  DeviceArray<std::uint32_t> heads(static_cast<std::size_t>(n), stream), scanned(static_cast<std::size_t>(n), stream);
  const Id points = count_groups(sorted, heads, scanned, n, stream);
  generate::check_contour_output(opt, points, n / 3);  // --max-memory, before the host mesh is allocated
  DeviceArray<K> unique_keys(static_cast<std::size_t>(points), stream);
  DeviceArray<std::uint32_t> group_begin(static_cast<std::size_t>(points), stream);
  DeviceArray<std::uint32_t> index_map(static_cast<std::size_t>(n), stream);
  groups_kernel<K><<<grid_for(n), kThreads, 0, stream>>>(sorted.get(), perm.get(), scanned.get(), unique_keys.get(),
                                                         group_begin.get(), index_map.get(), n);
  KEYMESH_CUDA_LAUNCHED("grouping");
  KEYMESH_CUDA_CHECK(cudaStreamSynchronize(stream), "KEY-REDUCE");
  st.weld += seconds_since(t0);

  // Stages 4 and 5: points and fields.
  t0 = Clock::now();
  const EdgeInterpolator<T> interp{samples.get(), s, isovalues.get(), static_cast<Id>(keys_per_iso)};
  DeviceArray<float> xyz(static_cast<std::size_t>(3 * points), stream);
  DeviceArray<float> scalar(opt.scalars ? static_cast<std::size_t>(points) : 0, stream);
  DeviceArray<float> normal(opt.normals != generate::ContourNormals::None ? static_cast<std::size_t>(3 * points) : 0,
                            stream);
  points_kernel<T, K><<<grid_for(points), kThreads, 0, stream>>>(
      interp, unique_keys.get(), xyz.get(), opt.scalars ? scalar.get() : nullptr,
      opt.normals == generate::ContourNormals::Gradient ? normal.get() : nullptr, points);
  KEYMESH_CUDA_LAUNCHED("points");
  if (opt.normals == generate::ContourNormals::Average)
    average_normals(xyz, index_map, perm, group_begin, parts.blocks, n, points, normal, stream);
  SurfaceMesh mesh = download_mesh(grid, opt, points, n, xyz, index_map, scalar, normal, stream);
  st.fields += seconds_since(t0);
  return mesh;
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
  cudaStream_t stream;
  KEYMESH_CUDA_CHECK(cudaStreamCreate(&stream), "creating a stream");
  struct StreamGuard {
    cudaStream_t s;
    ~StreamGuard() { cudaStreamDestroy(s); }
  } guard{stream};
  // Peak device memory: the stream-ordered pool's high-water mark, reset
  // here (only resetting to zero is allowed) and read when done.
  int device = 0;
  KEYMESH_CUDA_CHECK(cudaGetDevice(&device), "querying the device");
  cudaMemPool_t pool;
  KEYMESH_CUDA_CHECK(cudaDeviceGetDefaultMemPool(&pool, device), "querying the memory pool");
  unsigned long long high = 0;  // cuuint64_t (the attribute is passed as void*)
  KEYMESH_CUDA_CHECK(cudaMemPoolSetAttribute(pool, cudaMemPoolAttrUsedMemHigh, &high),
                     "resetting the pool's high-water mark");
  const std::uint64_t key_range = 3ull * static_cast<std::uint64_t>(grid.num_points()) * opt.isovalues.size();
  SurfaceMesh mesh = visit_scalars(grid, [&](const auto* samples) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(samples)>>;
    if (key_range <= std::numeric_limits<std::uint32_t>::max())
      return contour_typed<std::uint32_t, T>(grid, samples, opt, st, stream);
    return contour_typed<std::uint64_t, T>(grid, samples, opt, st, stream);
  });
  KEYMESH_CUDA_CHECK(cudaMemPoolGetAttribute(pool, cudaMemPoolAttrUsedMemHigh, &high),
                     "reading the pool's high-water mark");
  st.device_peak_bytes = static_cast<std::uint64_t>(high);
  return mesh;
}

}  // namespace keymesh::cuda
