#pragma once
// Marching cubes on a voxel grid over the device layer (keymesh/device/): the
// sort plan, the paper's GPU baseline, written once for every device:
//   classify (a case per voxel) -> count (its triangles) -> exclusive scan
//   (64-bit: a volume's total cannot wrap) -> emit an edge key per triangle
//   corner, in voxel order -> stable radix sort of (key, corner) ->
//   run-length (one group per point, in key order) -> the index map is the
//   triangle list -> positions and fields once per point, from its key.
// The per-element arithmetic is contour_kernels.hpp's EdgeInterpolator, the
// CPU fast paths' own, so the mesh equals contour()'s bit for bit (points,
// triangles, fields; the same point order as its KEY-REDUCE plans): ctest
// runs this on the CPU device (tests/generate/contour/contour_device_test.cpp),
// the GPU on the CUDA device (src/cuda/contour_cuda.cu: cuda::contour from
// host samples, cuda::contour_device from samples already on the device,
// through contour_arrays_on, the mesh left there).
//
// Averaged normals sum each point's face normals in contour()'s order (even
// blocks of 4 voxel layers, then odd; corner order within), so they match too.
// Not on this path (refused by name, check_device_contour_options):
// VERTEX-WELD, per-point history, output arrays, slabs and ghost planes. Coarsening is
// contour_coarsened_on's (generate/coarsen/coarsen_device.hpp): these entries
// refuse it, and with it on the arrays carry each point's coarse key.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "keymesh/core/device.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/device/algorithms.hpp"
#include "keymesh/device/key_groups.hpp"
#include "keymesh/generate/device_normals.hpp"
#include "keymesh/generate/device_surface.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/contour/contour_kernels.hpp"
#include "keymesh/generate/contour/layer_blocks.hpp"
#include "keymesh/generate/contour/marching_cubes_table.hpp"
#include "keymesh/mesh/face_normal.hpp"

namespace keymesh::generate {

// Key width of the device path: the narrowest that holds the keys (32 bits
// when 3 N x isovalues fits), or 64 bits always (what a volume past 2^32 / 3
// points needs; tests force it on small grids).
enum class DeviceKeys { Narrowest, Wide };

// The options this path refuses (InputError naming them, and what to use).
void check_device_contour_options(const ContourOptions& options);

// The fine contour's entries (contour_on, contour_arrays_on) refuse
// options.coarsen by name: `contour --coarsen` on a device is
// contour_coarsened_on (generate/coarsen/coarsen_device.hpp), whose mesh
// ends on the host. `entry` names the refusing entry.
void refuse_device_coarsen(const ContourOptions& options, const char* entry);

// contour() through the device path on the CPU device (with options.coarsen:
// contour_coarsened_on_cpu_device, generate/coarsen/coarsen_device.hpp).
SurfaceMesh contour_on_cpu_device(const ImageGrid& grid, const ContourOptions& options,
                                  ContourStats* stats = nullptr, DeviceKeys keys = DeviceKeys::Narrowest);

namespace device_contour {

// A voxel's grid point and indices: voxel v = i + (nx - 1) (j + (ny - 1) k).
struct Voxels {
  Id nx, nxy, vx, vy;
  KEYMESH_HD Id first_point(Id v, Id& i, Id& j, Id& k) const {
    i = v % vx;
    const Id r = v / vx;
    j = r % vy;
    k = r / vy;
    return i + nx * j + nxy * k;
  }
};

// Stage 1: every voxel's case (bit c: corner c inside, value >= iso) and
// triangle count. mode: 0 compare, 1 no sample inside, 2 every sample inside
// (InsideTest's none / all).
template <class T>
struct Classify {
  const T* samples;
  Voxels g;
  T threshold;
  int mode;
  const MarchingCubesTable* table;
  std::uint8_t* cases;
  std::uint8_t* counts;
  KEYMESH_HD void operator()(Id v) const {
    Id i, j, k;
    const Id p0 = g.first_point(v, i, j, k);
    unsigned c = 0;
    for (int corner = 0; corner < 8; ++corner) {
      const Id q = p0 + (corner & 1) + g.nx * ((corner >> 1) & 1) + g.nxy * ((corner >> 2) & 1);
      const bool in = mode == 2 || (mode == 0 && samples[q] >= threshold);
      c |= static_cast<unsigned>(in) << corner;
    }
    cases[v] = static_cast<std::uint8_t>(c);
    counts[v] = table->triangle_count[c];
  }
};

// Stage 2: the edge key of every triangle corner of voxel v, at its first
// triangle (the scan), in the table's corner order: contour()'s soup.
template <class K>
struct EmitKeys {
  const std::uint8_t* cases;
  const std::uint64_t* first;
  const MarchingCubesTable* table;
  Voxels g;
  K key_offset;  // the isovalue's index x 3N
  K* keys;       // the isovalue's part of the soup
  KEYMESH_HD void operator()(Id v) const {
    const unsigned c = cases[v];
    const int corners = 3 * table->triangle_count[c];
    if (corners == 0) return;
    Id i, j, k;
    const K voxel_key = key_offset + static_cast<K>(3 * g.first_point(v, i, j, k));
    K* o = keys + 3 * first[v];
    for (int n = 0; n < corners; ++n) {
      const CubeEdge& ce = table->edges[table->triangle_edges[c][n]];
      o[n] = voxel_key + static_cast<K>(3 * (ce.dx + ce.dy * g.nx + ce.dz * g.nxy) + ce.axis);
    }
  }
};

// The first corner of every block of kSlabsPerBlock voxel layers.
struct BlockStarts {
  const std::uint64_t* first;
  Id voxels_per_block;
  Id base;  // the isovalue's first corner
  Id* out;
  KEYMESH_HD void operator()(Id b) const { out[b] = base + 3 * static_cast<Id>(first[b * voxels_per_block]); }
};

// Where a point's values go (null: not asked for), and their arithmetic, as
// contour()'s PointWriter computes them (derivatives_at when curvature is
// asked for, whose gradient is gradient_at's): every device plan writes its
// points with this, so a point's bits do not depend on how its id was found.
template <class T>
struct PointOutputs {
  float* xyz;  // null when the positions come from elsewhere (VERTEX-WELD's welded points)
  float* scalar;
  float* gradient_normal;
  float* curvature;
  KEYMESH_HD void write(const EdgeInterpolator<T>& interp, const typename EdgeInterpolator<T>::Point& e,
                        Id p) const {
    if (xyz) interp.position(e, xyz + 3 * p);
    if (scalar) scalar[p] = interp.scalar(e);
    if (!gradient_normal && !curvature) return;
    double d[2][9];
    Id ijk1[3] = {e.ijk[0], e.ijk[1], e.ijk[2]};
    ++ijk1[e.axis];
    if (curvature) {
      interp.derivatives_at(e.p0, e.ijk, d[0], d[0] + 3);
      interp.derivatives_at(interp.far_end(e), ijk1, d[1], d[1] + 3);
      curvature[p] = interp.mean_curvature(e, d[0], d[0] + 3, d[1], d[1] + 3);
    } else {
      interp.gradient_at(e.p0, e.ijk, d[0]);
      interp.gradient_at(interp.far_end(e), ijk1, d[1]);
    }
    if (gradient_normal) interp.gradient_normal(e, d[0], d[1], gradient_normal + 3 * p);
  }
};

// Stage 4: position and fields of every point from its key.
template <class T, class K>
struct WritePoints {
  EdgeInterpolator<T> interp;
  const K* keys;
  PointOutputs<T> out;
  std::uint64_t* nearest;  // coarsening: the nearest grid point's key (contour()'s nearest_keys); null otherwise
  KEYMESH_HD void operator()(Id p) const {
    const auto e = interp.locate(static_cast<std::uint64_t>(keys[p]));
    out.write(interp, e, p);
    if (nearest)
      nearest[p] = static_cast<std::uint64_t>(keys[p]) / static_cast<std::uint64_t>(interp.keys_per_iso) *
                       static_cast<std::uint64_t>(interp.s.n) +
                   static_cast<std::uint64_t>(interp.nearest_point(e));
  }
};

// Stage 5's value of sorted position j for the blocks of one parity: its
// triangle's face normal, or zero (adding +0 leaves a sum that starts at +0
// unchanged, bit for bit) when its corner lies in a block of the other parity.
struct BlockedFace {
  const std::uint32_t* sorted_pairs;
  const Vec3f* face;
  const Id* blocks;  // block starts, ending with the corner count
  Id block_count;
  Id parity;
  KEYMESH_HD Vec3f operator()(Id j) const {
    const Id pair = sorted_pairs[j];
    Id lo = 0, hi = block_count;  // blocks[lo] <= pair < blocks[lo + 1]
    while (hi - lo > 1) {
      const Id mid = (lo + hi) / 2;
      if (blocks[mid] <= pair) lo = mid;
      else hi = mid;
    }
    return (lo & 1) == parity ? face[pair / 3] : Vec3f{0, 0, 0};
  }
};

// What the stages share: the input where the device reads it, the case table
// and the isovalues in device memory.
template <class D, class T>
struct Input {
  typename D::template Array<T> copy;  // the samples, on a device with memory of its own
  const T* samples = nullptr;
  typename D::template Array<MarchingCubesTable> table;
  typename D::template Array<double> isovalues;
  GridShape shape{};
  Voxels voxels{};
  Id voxel_count = 0;
};

// The samples are the device's own when `resident` (a non-owning view: no
// copy) or when the device's memory is the host's; uploaded otherwise.
template <class D, class T>
Input<D, T> prepare_input(const D& d, const ImageGrid& grid, const T* samples, bool resident, const ContourOptions& opt) {
  Input<D, T> in;
  GridShape& s = in.shape;
  s.nx = grid.dims[0], s.ny = grid.dims[1], s.nz = grid.dims[2];
  s.nxy = s.nx * s.ny, s.n = s.nxy * s.nz;
  for (int a = 0; a < 3; ++a) s.origin[a] = grid.origin[a], s.spacing[a] = grid.spacing[a];
  s.stride[0] = 1, s.stride[1] = s.nx, s.stride[2] = s.nxy;
  for (int a = 0; a < 3; ++a) s.offset[a] = opt.position_offset[a];
  s.table = nullptr;  // the host's; the kernels read the device's copy
  s.reversed_axes = opt.reversed_axes;
  in.voxels = Voxels{s.nx, s.nxy, s.nx - 1, s.ny - 1};
  in.voxel_count = (s.nx - 1) * (s.ny - 1) * (s.nz - 1);
  if (D::kHostMemory || resident) {
    in.samples = samples;
  } else {
    in.copy = d.upload(samples, s.n);
    in.samples = in.copy.data();
  }
  in.table = d.upload(&marching_cubes_table(opt.reversed_axes), 1);
  in.isovalues = d.upload(opt.isovalues.data(), static_cast<Id>(opt.isovalues.size()));
  return in;
}

// Per-voxel scratch reused by every isovalue.
template <class D>
struct VoxelScratch {
  typename D::template Array<std::uint8_t> cases, counts;
  typename D::template Array<std::uint64_t> first;  // exclusive scan of counts
};

// Stage 1 and the scan for one isovalue: its triangle count (64-bit).
template <class D, class T>
std::uint64_t count_isovalue(const D& d, const Input<D, T>& in, double iso, VoxelScratch<D>& v, ContourStats& st) {
  const InsideTest<T> test(iso);
  const auto mark = d.begin_stage(&st.classify);
  d.for_each(in.voxel_count, Classify<T>{in.samples, in.voxels, test.threshold, test.all ? 2 : (test.none ? 1 : 0),
                                         in.table.data(), v.cases.data(), v.counts.data()});
  d.end_stage(mark);  // the scan reads its total back: it counts in the generate stage
  return d.exclusive_scan(v.counts.data(), v.first.data(), in.voxel_count);
}

// The soup of every isovalue, one after the other (contour()'s order), and
// the blocks averaged normals are summed by.
template <class D, class K>
struct Soup {
  typename D::template Array<K> keys;
  typename D::template Array<Id> blocks;  // block starts, then the corner count
  Id corners = 0;
};

template <class D, class K, class T>
Soup<D, K> emit_soup(const D& d, const Input<D, T>& in, const ContourOptions& opt, ContourStats& st) {
  const Id n_iso = static_cast<Id>(opt.isovalues.size());
  VoxelScratch<D> v{d.template allocate<std::uint8_t>(in.voxel_count), d.template allocate<std::uint8_t>(in.voxel_count),
                    d.template allocate<std::uint64_t>(in.voxel_count)};
  // The total first, checked before anything is sized from it; with one
  // isovalue the counts stay for the emit, with several they are recounted.
  std::uint64_t total = 0;
  for (Id iso = 0; iso < n_iso; ++iso) total += count_isovalue(d, in, opt.isovalues[iso], v, st);
  check_contour_output(opt, 0, static_cast<Id>(total));  // 2^32 - 1 corners, --max-memory: contour()'s message
  const Id layer_blocks = (in.shape.nz - 1 + kSlabsPerBlock - 1) / kSlabsPerBlock;
  Soup<D, K> soup{d.template allocate<K>(3 * static_cast<Id>(total)), d.template allocate<Id>(n_iso * layer_blocks + 1),
                  3 * static_cast<Id>(total)};
  const K keys_per_iso = static_cast<K>(3 * in.shape.n);
  Id base = 0;
  for (Id iso = 0; iso < n_iso; ++iso) {
    const std::uint64_t triangles = n_iso == 1 ? total : count_isovalue(d, in, opt.isovalues[iso], v, st);
    const auto mark = d.begin_stage(&st.generate);
    d.for_each(layer_blocks, BlockStarts{v.first.data(), kSlabsPerBlock * in.voxels.vx * in.voxels.vy, base,
                                         soup.blocks.data() + iso * layer_blocks});
    d.for_each(in.voxel_count, EmitKeys<K>{v.cases.data(), v.first.data(), in.table.data(), in.voxels,
                                           static_cast<K>(iso) * keys_per_iso, soup.keys.data() + base});
    d.end_stage(mark);
    base += 3 * static_cast<Id>(triangles);
  }
  device::fill(d, soup.blocks.data() + n_iso * layer_blocks, 1, soup.corners);
  return soup;
}

// Stage 5: each point's face normals summed in contour()'s block order, made unit.
template <class D, class K>
typename D::template Array<float> averaged_normals(const D& d, const device::KeyGroups<D, K>& g, const Soup<D, K>& soup,
                                                   const float* xyz, const PointIndex* triangles) {
  const auto face = device_normals::face_normals(d, xyz, triangles, soup.corners / 3);
  auto normals = device_normals::zero_sums(d, g.groups);
  const Id block_count = static_cast<Id>(soup.blocks.size()) - 1;
  for (Id parity = 0; parity < 2; ++parity)
    device::segmented_reduce(d, g.offsets.data(), g.groups,
                             BlockedFace{g.sorted_pairs.data(), face.data(), soup.blocks.data(), block_count, parity},
                             device_normals::Add{}, reinterpret_cast<Vec3f*>(normals.data()));
  device_normals::make_unit(d, normals.data(), g.groups);
  return normals;
}

// The mesh's fields in contour()'s order: the scalar, gradient normals,
// curvature, then averaged normals.
template <class D>
struct PointFields {
  typename D::template Array<float> scalar, gradient_normal, curvature, averaged_normal;
};

// The mesh as the stages leave it, in the device's memory (the points and
// fields from allocate_output, the triangles group_keys' index map).
template <class D>
struct ContourArrays {
  typename D::template Array<float> xyz;
  typename D::template Array<std::uint32_t> connectivity;
  PointFields<D> fields;
  // With options.coarsen: every point's coarse key, the grid point nearest
  // it on its edge + isovalue index x N (contour()'s nearest_keys), for
  // coarsen_device.hpp to merge by; the averaged normals are left to it.
  typename D::template Array<std::uint64_t> nearest;
  Id points = 0, triangles = 0;
};

// The mesh's point arrays for out.points points (positions when `with_xyz`;
// the fields asked for), allocated, and where the point writer puts them.
template <class T, class D>
PointOutputs<T> point_outputs(const D& d, ContourArrays<D>& out, const ContourOptions& opt, bool with_xyz) {
  const bool gradient = opt.normals == ContourNormals::Gradient;
  const Id points = out.points;
  if (with_xyz) out.xyz = d.template allocate_output<float>(3 * points);
  PointFields<D>& f = out.fields;
  f.scalar = d.template allocate_output<float>(opt.scalars ? points : 0);
  f.gradient_normal = d.template allocate_output<float>(gradient ? 3 * points : 0);
  f.curvature = d.template allocate_output<float>(opt.curvature ? points : 0);
  return PointOutputs<T>{with_xyz ? out.xyz.data() : nullptr, opt.scalars ? f.scalar.data() : nullptr,
                         gradient ? f.gradient_normal.data() : nullptr, opt.curvature ? f.curvature.data() : nullptr};
}

// Stages 4 and 5: positions and fields of every point, from its key.
template <class D, class K, class T>
void write_points(const D& d, const Input<D, T>& in, const device::KeyGroups<D, K>& g, const Soup<D, K>& soup,
                  const ContourOptions& opt, ContourArrays<D>& out) {
  const EdgeInterpolator<T> interp{in.samples, in.shape, in.isovalues.data(), 3 * in.shape.n};
  out.nearest = d.template allocate<std::uint64_t>(opt.coarsen ? out.points : 0);
  d.for_each(out.points, WritePoints<T, K>{interp, g.unique_keys.data(), point_outputs<T>(d, out, opt, true),
                                           opt.coarsen ? out.nearest.data() : nullptr});
  if (opt.normals == ContourNormals::Average && !opt.coarsen)
    out.fields.averaged_normal = averaged_normals(d, g, soup, out.xyz.data(), g.index_map.data());
}

template <class D, class K, class T>
ContourArrays<D> contour_arrays_typed(const D& d, const ImageGrid& grid, const T* samples, bool resident,
                                      const ContourOptions& opt, ContourStats& st) {
  auto mark = d.begin_stage(&st.generate);
  const Input<D, T> in = prepare_input(d, grid, samples, resident, opt);
  d.end_stage(mark);
  st.key_bits = static_cast<int>(sizeof(K) * 8);
  Soup<D, K> soup = emit_soup<D, K>(d, in, opt, st);
  st.soup_points = soup.corners;
  const K key_range = static_cast<K>(opt.isovalues.size()) * static_cast<K>(3 * in.shape.n);
  int key_bits = 0;
  while (key_bits < int(sizeof(K) * 8) && ((key_range - 1) >> key_bits) != 0) ++key_bits;
  mark = d.begin_stage(&st.weld);
  device::KeyGroups<D, K> g = device::group_keys(d, soup.keys.data(), soup.corners, key_bits);
  d.end_stage(mark);
  ContourArrays<D> out;
  out.points = g.groups;
  out.triangles = soup.corners / 3;
  check_contour_output(opt, out.points, out.triangles);
  mark = d.begin_stage(&st.fields);
  write_points(d, in, g, soup, opt, out);
  d.end_stage(mark);
  out.connectivity = std::move(g.index_map);
  return out;
}

// The fields asked for, named, in contour()'s order (the scalar, gradient
// normals, curvature, then averaged normals; none when coarsening), even
// when empty (no points).
template <class D>
std::vector<device_surface::Field<D>> point_fields(PointFields<D>&& f, const std::string& scalar_name,
                                                   const ContourOptions& opt) {
  std::vector<device_surface::Field<D>> out;
  if (opt.scalars) out.push_back({scalar_name, 1, std::move(f.scalar)});
  if (opt.normals == ContourNormals::Gradient) out.push_back({"Normals", 3, std::move(f.gradient_normal)});
  if (opt.curvature) out.push_back({"mean_curvature", 1, std::move(f.curvature)});
  if (opt.normals == ContourNormals::Average && !opt.coarsen) out.push_back({"Normals", 3, std::move(f.averaged_normal)});
  return out;
}

// The arrays brought to the host as contour()'s mesh. The download counts
// in the fields stage.
template <class D>
SurfaceMesh to_host_mesh(const D& d, ContourArrays<D>&& a, const std::string& scalar_name, const ContourOptions& opt,
                         ContourStats& st) {
  const auto mark = d.begin_stage(&st.fields);
  SurfaceMesh mesh;
  mesh.points = d.to_host(std::move(a.xyz));
  mesh.connectivity = d.to_host(std::move(a.connectivity));
  for (device_surface::Field<D>& f : point_fields(std::move(a.fields), scalar_name, opt))
    mesh.point_fields.push_back(Field{f.name, f.components, d.to_host(std::move(f.values))});
  d.end_stage(mark);
  return mesh;
}

// A mesh contoured over a C-ordered array's reversed axes mirrored back into
// the array's frame, as the Python module's mirror_axes does on the host:
// x <-> z in points and in the 3-component field (normals), corners 1 and 2
// of every triangle swapped (a mirror turns orientation).
struct MirrorBack {
  float* xyz;
  float* normals;  // null when there are none
  std::uint32_t* connectivity;
  Id points, triangles;
  KEYMESH_HD static void swap_x_z(float* v) {
    const float x = v[0];
    v[0] = v[2], v[2] = x;
  }
  KEYMESH_HD void operator()(Id i) const {
    if (i < points) {
      swap_x_z(xyz + 3 * i);
      if (normals) swap_x_z(normals + 3 * i);
    }
    if (i < triangles) {
      const std::uint32_t b = connectivity[3 * i + 1];
      connectivity[3 * i + 1] = connectivity[3 * i + 2], connectivity[3 * i + 2] = b;
    }
  }
};

// contour()'s input checks (check_contour_input) and the device path's
// refusals, then the arrays (stats reset first) of the grid's samples,
// grid.data(): host memory, or the device's when `resident` (contour_arrays_on's
// view). Dispatches on the grid's sample type and the key width the key range
// needs (64-bit where the caller asks for it).
template <class D>
ContourArrays<D> checked_contour_arrays(const D& d, const ImageGrid& grid, bool resident, const ContourOptions& options,
                                        ContourStats& st, DeviceKeys keys) {
  check_contour_input(grid, options);
  check_device_contour_options(options);
  st = ContourStats{};
  const std::uint64_t key_range = 3ull * static_cast<std::uint64_t>(grid.num_points()) * options.isovalues.size();
  const bool narrow = keys == DeviceKeys::Narrowest && key_range <= std::numeric_limits<std::uint32_t>::max();
  return visit_scalars(grid, [&](const auto* samples) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(samples)>>;
    if (narrow) return contour_arrays_typed<D, std::uint32_t, T>(d, grid, samples, resident, options, st);
    return contour_arrays_typed<D, std::uint64_t, T>(d, grid, samples, resident, options, st);
  });
}

// The grid's description (dims, spacing, origin, type, name) over samples
// in the device's memory, a non-owning view (contour_arrays_on's input).
inline ImageGrid samples_view(const ImageGrid& grid, const void* samples) {
  if (!samples) throw InputError("contour: the volume's samples pointer is null");
  ImageGrid view;
  view.dims = grid.dims, view.origin = grid.origin, view.spacing = grid.spacing;
  view.type = grid.type, view.name = grid.name;
  view.external = static_cast<const std::byte*>(samples);
  return view;
}

}  // namespace device_contour

// The device path on device `d`: options checked as contour() checks them
// (check_contour_input) and refused where this path lacks them.
template <class D>
SurfaceMesh contour_on(const D& d, const ImageGrid& grid, const ContourOptions& options, ContourStats* stats,
                       DeviceKeys keys = DeviceKeys::Narrowest) {
  refuse_device_coarsen(options, "contour_on");
  ContourStats local;
  ContourStats& st = stats ? *stats : local;
  auto arrays = device_contour::checked_contour_arrays(d, grid, false, options, st, keys);
  return device_contour::to_host_mesh(d, std::move(arrays), grid.name, options, st);
}

// The device path on samples already in the device's memory (a non-owning
// view: nothing is uploaded), the mesh left there as device arrays (the
// points and fields from allocate_output: on the CUDA device, memory the
// caller may keep). `grid` gives the dims, spacing, origin, type and name;
// its own samples are not read. On the CPU device the samples are host
// memory: ctest runs this entry there (tests/generate/contour/).
template <class D>
device_contour::ContourArrays<D> contour_arrays_on(const D& d, const ImageGrid& grid, const void* samples,
                                                   const ContourOptions& options, ContourStats* stats,
                                                   DeviceKeys keys = DeviceKeys::Narrowest) {
  const ImageGrid view = device_contour::samples_view(grid, samples);
  refuse_device_coarsen(options, "contour_arrays_on");
  ContourStats local;
  return device_contour::checked_contour_arrays(d, view, true, options, stats ? *stats : local, keys);
}

// Mirrors the arrays back (device_contour::MirrorBack) on the device.
template <class D>
void mirror_back(const D& d, device_contour::ContourArrays<D>& a) {
  float* normals = a.fields.gradient_normal.size() ? a.fields.gradient_normal.data()
                                                   : (a.fields.averaged_normal.size() ? a.fields.averaged_normal.data()
                                                                                      : nullptr);
  d.for_each(a.points > a.triangles ? a.points : a.triangles,
             device_contour::MirrorBack{a.xyz.data(), normals, a.connectivity.data(), a.points, a.triangles});
}

}  // namespace keymesh::generate
