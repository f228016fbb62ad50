// The CUDA backend of marching cubes + KEY-REDUCE (see keymesh/cuda/backend.hpp).
//
// The stages mirror the CPU backend and share its per-element functors
// (keymesh/generate/contour/contour_kernels.hpp), compiled here for the device with
// --fmad=false so that every floating-point operation rounds as on the CPU:
//   1. classify: one thread per voxel, its case and triangle count;
//   2. scan the counts (CUB), emit the soup of edge keys in voxel order (the
//      CPU's order, so the index map, the triangle list, comes out the same);
//   3. KEY-REDUCE, sort plan: stable radix sort of (key, pair) pairs (CUB) on
//      the significant key bits, heads of equal keys, an inclusive scan: the
//      groups in increasing key order, as the CPU's dense and sort plans give;
//   4. positions and fields once per group, from its key;
//   5. averaged normals: each point sums its triangles' normals in the CPU's
//      fixed order (even slab blocks, then odd; pair order within a block).
// Device memory comes from CUDA's stream-ordered pool (cudaMallocAsync), so
// buffers freed by a stage are reused by the next without new allocations.
#include <cuda_runtime.h>

#include <chrono>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

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

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw InputError(std::string("--backend cuda: ") + what + ": " + cudaGetErrorString(e));
}

// A device array from the stream-ordered pool.
template <class T>
class DeviceArray {
 public:
  DeviceArray(std::size_t n, cudaStream_t s) : n_(n), s_(s) {
    if (n) check(cudaMallocAsync(reinterpret_cast<void**>(&p_), n * sizeof(T), s), "allocating device memory");
  }
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  ~DeviceArray() {
    if (p_) cudaFreeAsync(p_, s_);
  }
  T* get() const { return p_; }
  std::size_t size() const { return n_; }
  void upload(const T* host, std::size_t n) {
    check(cudaMemcpyAsync(p_, host, n * sizeof(T), cudaMemcpyHostToDevice, s_), "uploading");
  }
  void download(T* host, std::size_t n) const {
    check(cudaMemcpyAsync(host, p_, n * sizeof(T), cudaMemcpyDeviceToHost, s_), "downloading");
  }

 private:
  T* p_ = nullptr;
  std::size_t n_;
  cudaStream_t s_;
};

__constant__ generate::MarchingCubesTable d_table;

constexpr int kThreads = 256;
unsigned grid_for(Id n) { return static_cast<unsigned>((n + kThreads - 1) / kThreads); }

// Stage 1: case and triangle count of every voxel. mode: 0 compare, 1 none inside, 2 all inside.
template <class T>
__global__ void classify_kernel(const T* samples, GridShape s, T threshold, int mode, std::uint8_t* cases,
                                std::uint32_t* counts, Id voxels) {
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
  counts[v] = d_table.triangle_count[c];
}

// Stage 2: the soup, an edge key per triangle corner, in voxel order.
template <class K>
__global__ void emit_kernel(const std::uint8_t* cases, const std::uint32_t* offsets, GridShape s, K key_offset,
                            K* keys, Id voxels) {
  const Id v = static_cast<Id>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (v >= voxels) return;
  const unsigned c = cases[v];
  const int corners = 3 * d_table.triangle_count[c];
  if (corners == 0) return;
  const Id i = v % (s.nx - 1), r = v / (s.nx - 1), j = r % (s.ny - 1), k = r / (s.ny - 1);
  const K voxel_key = key_offset + static_cast<K>(3 * (i + s.nx * j + s.nxy * k));
  K* o = keys + 3 * static_cast<Id>(offsets[v]);
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

// The grid's voxels; LimitError past CUB's int sizes.
Id voxels_of(const GridShape& s) {
  const Id voxels = (s.nx - 1) * (s.ny - 1) * (s.nz - 1);
  if (voxels > Id{std::numeric_limits<int>::max()})
    throw LimitError("--backend cuda: " + std::to_string(voxels) + " voxels exceed 2^31 - 1 (use the CPU backend)");
  return voxels;
}

// Stage 1's arrays, one entry per voxel, reused by every isovalue: its case,
// its triangle count and the count's exclusive scan (its first triangle).
struct VoxelCases {
  VoxelCases(Id voxels, cudaStream_t stream)
      : cases(static_cast<std::size_t>(voxels), stream),
        counts(static_cast<std::size_t>(voxels), stream),
        offsets(static_cast<std::size_t>(voxels), stream) {}
  DeviceArray<std::uint8_t> cases;
  DeviceArray<std::uint32_t> counts, offsets;
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

// After stage 1's scan: the isovalue's triangles, and the first triangle of
// every 4th voxel slab. Waits for the stream.
struct TriangleOffsets {
  Id triangles = 0;
  std::vector<std::uint32_t> slab_first;
};

TriangleOffsets download_offsets(const VoxelCases& v, const GridShape& s, Id voxels, cudaStream_t stream) {
  std::uint32_t last_offset = 0, last_count = 0;
  check(cudaMemcpyAsync(&last_offset, v.offsets.get() + voxels - 1, 4, cudaMemcpyDeviceToHost, stream), "downloading");
  check(cudaMemcpyAsync(&last_count, v.counts.get() + voxels - 1, 4, cudaMemcpyDeviceToHost, stream), "downloading");
  TriangleOffsets out;
  for (Id k = 0; k < s.nz - 1; k += 4) out.slab_first.push_back(0);
  for (std::size_t b = 0; b < out.slab_first.size(); ++b)
    check(cudaMemcpyAsync(&out.slab_first[b], v.offsets.get() + Id(b) * 4 * (s.ny - 1) * (s.nx - 1), 4,
                          cudaMemcpyDeviceToHost, stream),
          "downloading");
  check(cudaStreamSynchronize(stream), "classify");
  out.triangles = Id{last_offset} + Id{last_count};
  return out;
}

// Stages 1 and 2 for one isovalue: classify the voxels, scan their triangle
// counts, and emit this isovalue's part of the soup (keys + key_offset),
// appended to `parts` with its slab blocks.
template <class K, class T>
void emit_isovalue(const T* samples, const GridShape& s, Id voxels, double isovalue, K key_offset, VoxelCases& v,
                   SoupParts<K>& parts, cudaStream_t stream) {
  const generate::InsideTest<T> test(isovalue);
  classify_kernel<T><<<grid_for(voxels), kThreads, 0, stream>>>(samples, s, test.threshold,
                                                                 test.all ? 2 : (test.none ? 1 : 0), v.cases.get(),
                                                                 v.counts.get(), voxels);
  check(cudaGetLastError(), "classify");
  // The scan's storage is freed when this isovalue is done, after its part is allocated.
  std::size_t temp_bytes = 0;
  cub::DeviceScan::ExclusiveSum(nullptr, temp_bytes, v.counts.get(), v.offsets.get(), static_cast<int>(voxels), stream);
  DeviceArray<std::uint8_t> temp(temp_bytes, stream);
  check(cub::DeviceScan::ExclusiveSum(temp.get(), temp_bytes, v.counts.get(), v.offsets.get(),
                                      static_cast<int>(voxels), stream),
        "scanning triangle counts");
  const TriangleOffsets counted = download_offsets(v, s, voxels, stream);
  const Id triangles = counted.triangles;
  if (parts.corners + 3 * triangles > Id{std::numeric_limits<int>::max()})
    throw LimitError("--backend cuda: " + std::to_string((parts.corners + 3 * triangles) / 3) +
                     " triangles exceed the device sort's 2^31 - 1 corners (use the CPU backend)");
  for (std::uint32_t first : counted.slab_first) parts.blocks.push_back(parts.corners + 3 * Id{first});
  parts.keys.push_back(std::make_unique<DeviceArray<K>>(static_cast<std::size_t>(3 * triangles), stream));
  DeviceArray<K>* part = parts.keys.back().get();
  parts.size.push_back(3 * triangles);
  if (triangles > 0) {
    emit_kernel<K><<<grid_for(voxels), kThreads, 0, stream>>>(v.cases.get(), v.offsets.get(), s, key_offset,
                                                              part->get(), voxels);
    check(cudaGetLastError(), "emit");
  }
  parts.corners += 3 * triangles;
}

// One soup: the parts end to end, then the parts freed.
template <class K>
void join_parts(SoupParts<K>& parts, DeviceArray<K>& soup, cudaStream_t stream) {
  Id at = 0;
  for (std::size_t k = 0; k < parts.keys.size(); ++k) {
    if (parts.size[k])
      check(cudaMemcpyAsync(soup.get() + at, parts.keys[k]->get(), parts.size[k] * sizeof(K),
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
  int end_bit = 0;
  while (end_bit < int(sizeof(K) * 8) && ((key_range - 1) >> end_bit) != 0) ++end_bit;
  std::size_t temp_bytes = 0;
  cub::DeviceRadixSort::SortPairs(nullptr, temp_bytes, soup.get(), sorted.get(), pair_in.get(), perm.get(), n, 0,
                                  std::max(end_bit, 1), stream);
  DeviceArray<std::uint8_t> temp(temp_bytes, stream);
  check(cub::DeviceRadixSort::SortPairs(temp.get(), temp_bytes, soup.get(), sorted.get(), pair_in.get(), perm.get(),
                                        n, 0, std::max(end_bit, 1), stream),
        "sorting the soup");
}

// Stage 3b: 1 where a run of equal sorted keys starts, scanned inclusively
// (each position's group + 1); returns the number of groups. Waits for the stream.
template <class K>
Id count_groups(const DeviceArray<K>& sorted, DeviceArray<std::uint32_t>& heads, DeviceArray<std::uint32_t>& scanned,
                int n, cudaStream_t stream) {
  heads_kernel<K><<<grid_for(n), kThreads, 0, stream>>>(sorted.get(), heads.get(), n);
  {
    std::size_t temp_bytes = 0;
    cub::DeviceScan::InclusiveSum(nullptr, temp_bytes, heads.get(), scanned.get(), n, stream);
    DeviceArray<std::uint8_t> temp(temp_bytes, stream);
    check(cub::DeviceScan::InclusiveSum(temp.get(), temp_bytes, heads.get(), scanned.get(), n, stream),
          "scanning group heads");
  }
  std::uint32_t groups = 0;
  check(cudaMemcpyAsync(&groups, scanned.get() + n - 1, 4, cudaMemcpyDeviceToHost, stream), "downloading");
  check(cudaStreamSynchronize(stream), "KEY-REDUCE");
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
  DeviceArray<Id> d_blocks(blocks.size(), stream);
  d_blocks.upload(blocks.data(), blocks.size());
  average_kernel<<<grid_for(points), kThreads, 0, stream>>>(perm.get(), group_begin.get(), n, face.get(),
                                                            d_blocks.get(), static_cast<Id>(blocks.size()) - 1,
                                                            normal.get(), points);
  check(cudaGetLastError(), "averaging normals");
  check(cudaStreamSynchronize(stream), "averaging normals");
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
  check(cudaStreamSynchronize(stream), "downloading the mesh");
  return mesh;
}

// The stages in order. Every device array lives to the end, as the stages
// allocate them (the pool's high-water mark is the report's peak).
template <class K, class T>
SurfaceMesh contour_typed(const ImageGrid& grid, const T* host_samples, const generate::ContourOptions& opt,
                          generate::ContourStats& st, cudaStream_t stream) {
  const GridShape s = shape_of(grid);
  const Id voxels = voxels_of(s);
  const Id n_iso = static_cast<Id>(opt.isovalues.size());
  const K keys_per_iso = static_cast<K>(3 * s.n);
  const K key_range = static_cast<K>(n_iso) * keys_per_iso;
  st.key_bits = static_cast<int>(sizeof(K) * 8);

  auto t0 = Clock::now();
  DeviceArray<T> samples(static_cast<std::size_t>(s.n), stream);
  samples.upload(host_samples, static_cast<std::size_t>(s.n));
  DeviceArray<double> isovalues(opt.isovalues.size(), stream);
  isovalues.upload(opt.isovalues.data(), opt.isovalues.size());
  check(cudaMemcpyToSymbolAsync(d_table, &generate::marching_cubes_table(opt.reversed_axes),
                                sizeof(generate::MarchingCubesTable), 0, cudaMemcpyHostToDevice, stream),
        "uploading the case table");

  // Stages 1 and 2, per isovalue; the soup grows iso after iso, as on the CPU.
  VoxelCases cases(voxels, stream);
  SoupParts<K> parts;
  for (Id iso_index = 0; iso_index < n_iso; ++iso_index)
    emit_isovalue<K, T>(samples.get(), s, voxels, opt.isovalues[iso_index], static_cast<K>(iso_index) * keys_per_iso,
                        cases, parts, stream);
  parts.blocks.push_back(parts.corners);
  st.soup_points = parts.corners;
  DeviceArray<K> soup(static_cast<std::size_t>(parts.corners), stream);
  join_parts(parts, soup, stream);
  check(cudaStreamSynchronize(stream), "generate");
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
  DeviceArray<K> unique_keys(static_cast<std::size_t>(points), stream);
  DeviceArray<std::uint32_t> group_begin(static_cast<std::size_t>(points), stream);
  DeviceArray<std::uint32_t> index_map(static_cast<std::size_t>(n), stream);
  groups_kernel<K><<<grid_for(n), kThreads, 0, stream>>>(sorted.get(), perm.get(), scanned.get(), unique_keys.get(),
                                                         group_begin.get(), index_map.get(), n);
  check(cudaGetLastError(), "grouping");
  check(cudaStreamSynchronize(stream), "KEY-REDUCE");
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
  check(cudaGetLastError(), "points");
  if (opt.normals == generate::ContourNormals::Average)
    average_normals(xyz, index_map, perm, group_begin, parts.blocks, n, points, normal, stream);
  SurfaceMesh mesh = download_mesh(grid, opt, points, n, xyz, index_map, scalar, normal, stream);
  st.fields += seconds_since(t0);
  return mesh;
}

}  // namespace

bool compiled() { return true; }

bool available(std::string* why) {
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
  std::string why;
  if (!available(&why)) throw InputError("--backend cuda: " + why);
  if (opt.weld == generate::ContourWeld::VertexWeld)
    throw InputError("--backend cuda: VERTEX-WELD is not available on the GPU yet (use --weld keyreduce)");
  if (opt.coarsen) throw InputError("--backend cuda: coarsening is not available on the GPU yet");
  if (opt.curvature) throw InputError("--backend cuda: curvature is not available on the GPU yet");
  generate::ContourStats local;
  generate::ContourStats& st = stats ? *stats : local;
  st = generate::ContourStats{};
  cudaStream_t stream;
  check(cudaStreamCreate(&stream), "creating a stream");
  struct StreamGuard {
    cudaStream_t s;
    ~StreamGuard() { cudaStreamDestroy(s); }
  } guard{stream};
  // Peak device memory: the stream-ordered pool's high-water mark, reset
  // here (only resetting to zero is allowed) and read when done.
  int device = 0;
  check(cudaGetDevice(&device), "querying the device");
  cudaMemPool_t pool;
  check(cudaDeviceGetDefaultMemPool(&pool, device), "querying the memory pool");
  unsigned long long high = 0;  // cuuint64_t (the attribute is passed as void*)
  check(cudaMemPoolSetAttribute(pool, cudaMemPoolAttrUsedMemHigh, &high), "resetting the pool's high-water mark");
  const std::uint64_t key_range = 3ull * static_cast<std::uint64_t>(grid.num_points()) * opt.isovalues.size();
  SurfaceMesh mesh = visit_scalars(grid, [&](const auto* samples) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(samples)>>;
    if (key_range <= std::numeric_limits<std::uint32_t>::max())
      return contour_typed<std::uint32_t, T>(grid, samples, opt, st, stream);
    return contour_typed<std::uint64_t, T>(grid, samples, opt, st, stream);
  });
  check(cudaMemPoolGetAttribute(pool, cudaMemPoolAttrUsedMemHigh, &high), "reading the pool's high-water mark");
  st.device_peak_bytes = static_cast<std::uint64_t>(high);
  return mesh;
}

}  // namespace keymesh::cuda
