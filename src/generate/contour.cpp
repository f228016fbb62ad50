#include "keymesh/generate/contour.hpp"

#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/generate/coarsen.hpp"
#include "keymesh/generate/contour_kernels.hpp"
#include "keymesh/generate/marching_cubes_table.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/keyreduce/reduce.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"
#include "keymesh/weld/vertex_weld.hpp"

namespace keymesh::generate {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

GridShape shape_of(const ImageGrid& g) {
  GridShape s{};
  s.nx = g.dims[0];
  s.ny = g.dims[1];
  s.nz = g.dims[2];
  s.nxy = s.nx * s.ny;
  s.n = s.nxy * s.nz;
  for (int a = 0; a < 3; ++a) {
    s.origin[a] = g.origin[a];
    s.spacing[a] = g.spacing[a];
  }
  s.stride[0] = 1;
  s.stride[1] = s.nx;
  s.stride[2] = s.nxy;
  return s;
}

// Inside bits of every grid row (j, k), one bit per sample, plus one zero
// word of padding so that "bit i + 1" can always be read.
struct InsideBits {
  Id words_per_row = 0;
  std::vector<std::uint64_t> words;
  const std::uint64_t* row(Id j, Id k, Id ny) const { return words.data() + (k * ny + j) * words_per_row; }
};

template <class T>
void classify(const T* samples, const GridShape& s, const InsideTest<T>& test, InsideBits& bits) {
  bits.words_per_row = (s.nx + 63) / 64 + 1;
  bits.words.assign(static_cast<std::size_t>(bits.words_per_row * s.ny * s.nz), 0);
  const Id rows = s.ny * s.nz;
  const Id full = s.nx / 64;
  const Id wpr = bits.words_per_row;
  parallel::for_each(rows, [&](Id r) {
    const T* in = samples + r * s.nx;
    std::uint64_t* out = bits.words.data() + r * wpr;
    if (test.none) return;
    if (test.all) {
      for (Id i = 0; i < s.nx; ++i) out[i >> 6] |= std::uint64_t{1} << (i & 63);
      return;
    }
    const T thr = test.threshold;
    for (Id q = 0; q < full; ++q) {
      // Compare into bytes (a loop the compiler vectorizes), then pack each
      // 8 bytes of 0/1 into 8 bits with one multiply: byte i lands on bit
      // 56 + i of the product, with no carries between the terms.
      const T* v = in + 64 * q;
      alignas(64) std::uint8_t flag[64];
      for (int b = 0; b < 64; ++b) flag[b] = static_cast<std::uint8_t>(v[b] >= thr);
      std::uint64_t w = 0;
      for (int g = 0; g < 8; ++g) {
        std::uint64_t x;
        std::memcpy(&x, flag + 8 * g, 8);
        w |= ((x * 0x0102040810204080ull) >> 56) << (8 * g);
      }
      out[q] = w;
    }
    std::uint64_t w = 0;
    for (Id i = 64 * full; i < s.nx; ++i) w |= static_cast<std::uint64_t>(in[i] >= thr) << (i & 63);
    if (s.nx % 64) out[full] = w;
  }, 64);
}

// Visits every voxel of voxel row (j, k) whose corners are not all on one
// side, in increasing i, calling f(i, cube_case). Whole 64-voxel words with
// no sign change are skipped with a few bit operations.
template <class F>
void for_each_cut_voxel(const InsideBits& bits, const GridShape& s, Id j, Id k, F&& f) {
  const std::uint64_t* r00 = bits.row(j, k, s.ny);
  const std::uint64_t* r10 = bits.row(j + 1, k, s.ny);
  const std::uint64_t* r01 = bits.row(j, k + 1, s.ny);
  const std::uint64_t* r11 = bits.row(j + 1, k + 1, s.ny);
  const Id voxels = s.nx - 1;
  const Id words = (voxels + 63) / 64;
  for (Id q = 0; q < words; ++q) {
    const std::uint64_t a = r00[q], b = r10[q], c = r01[q], d = r11[q];
    // Bits of corner i + 1: shift the next word in.
    const std::uint64_t a1 = (a >> 1) | (r00[q + 1] << 63);
    const std::uint64_t b1 = (b >> 1) | (r10[q + 1] << 63);
    const std::uint64_t c1 = (c >> 1) | (r01[q + 1] << 63);
    const std::uint64_t d1 = (d >> 1) | (r11[q + 1] << 63);
    std::uint64_t active = (a ^ b) | (a ^ c) | (a ^ d) | (a ^ a1) | (a ^ b1) | (a ^ c1) | (a ^ d1);
    const Id left = voxels - 64 * q;
    if (left < 64) active &= (std::uint64_t{1} << left) - 1;
    while (active) {
      const int bit = std::countr_zero(active);
      active &= active - 1;
      const unsigned cube_case = static_cast<unsigned>(((a >> bit) & 1) | (((a1 >> bit) & 1) << 1) |
                                                       (((b >> bit) & 1) << 2) | (((b1 >> bit) & 1) << 3) |
                                                       (((c >> bit) & 1) << 4) | (((c1 >> bit) & 1) << 5) |
                                                       (((d >> bit) & 1) << 6) | (((d1 >> bit) & 1) << 7));
      f(64 * q + bit, cube_case);
    }
  }
}

// Voxel slabs per block of the soup handed to keyreduce::reduce_blocked: a
// constant, so the blocks (and the merge order they imply) do not depend on
// the thread count.
constexpr Id kSlabsPerBlock = 4;

// One isovalue's triangle soup as edge keys, appended to `keys` with
// `key_offset` added (the isovalue's index times 3N). Appends to `blocks`
// the first pair of every kSlabsPerBlock voxel slabs: a point is shared only
// by the slabs on either side of its plane, so a block shares points with
// its two neighbours at most.
template <class K>
Id generate_soup(const InsideBits& bits, const GridShape& s, Id k_begin, Id k_end, K key_offset, std::vector<K>& keys,
                 std::vector<Id>& blocks, ContourStats& st) {
  // Voxel layers [k_begin, k_end): all of them but ghost planes' layers.
  const auto& table = marching_cubes_table();
  const Id rows = (s.ny - 1) * (k_end - k_begin);
  auto t0 = Clock::now();
  std::vector<Id> row_offsets(rows + 1, 0);
  parallel::for_each_dynamic(rows, [&](Id r) {
    const Id j = r % (s.ny - 1), k = k_begin + r / (s.ny - 1);
    Id count = 0;
    for_each_cut_voxel(bits, s, j, k, [&](Id, unsigned cube_case) { count += table.triangle_count[cube_case]; });
    row_offsets[r] = count;
  }, 8);
  const Id triangles = parallel::exclusive_scan(row_offsets.data(), row_offsets.data(), rows + 1);
  st.classify += seconds_since(t0);
  t0 = Clock::now();
  const Id base = static_cast<Id>(keys.size());
  for (Id k = 0; k < k_end - k_begin; k += kSlabsPerBlock) blocks.push_back(base + 3 * row_offsets[k * (s.ny - 1)]);
  if (base + 3 * triangles > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("contour: " + std::to_string(base / 3 + triangles) +
                     " triangles exceed the supported 1431655765 (2^32 - 1 corners)");
  keys.resize(static_cast<std::size_t>(base + 3 * triangles));
  // Key of each cube edge relative to the voxel's first corner.
  K edge_delta[12];
  for (int e = 0; e < 12; ++e) {
    const auto& ce = table.edges[e];
    edge_delta[e] = static_cast<K>(3 * (ce.dx + ce.dy * s.nx + ce.dz * s.nxy) + ce.axis);
  }
  K* out = keys.data() + base;
  parallel::for_each_dynamic(rows, [&](Id r) {
    const Id j = r % (s.ny - 1), k = k_begin + r / (s.ny - 1);
    K* o = out + 3 * row_offsets[r];
    const K row_key = key_offset + static_cast<K>(3 * (j * s.nx + k * s.nxy));
    for_each_cut_voxel(bits, s, j, k, [&](Id i, unsigned cube_case) {
      const K voxel_key = row_key + static_cast<K>(3 * i);
      const int corners = 3 * table.triangle_count[cube_case];
      const auto& edges = table.triangle_edges[cube_case];
      for (int c = 0; c < corners; ++c) *o++ = voxel_key + edge_delta[edges[c]];
    });
  }, 8);
  st.generate += seconds_since(t0);
  return triangles;
}

// Sum of the area-weighted normals of the triangles around each point,
// merged by KEY-REDUCE over the groups, then normalised (the transform).
// With `blocks` (slab blocks of the soup, see generate_soup) the sums are
// scattered block by block (keyreduce::reduce_blocked), with no pair order;
// otherwise (VERTEX-WELD's groups) reduced over the groups' pair order.
template <class K>
void average_normals(const keyreduce::Groups<K>& groups, const std::vector<Id>* blocks, const SurfaceMesh& mesh,
                     std::vector<float>& normals) {
  const float* P = mesh.points.data();
  const PointIndex* C = mesh.connectivity.data();
  auto face_normal = [P, C](Id t) { return triangle_normal(P, C, t); };
  const Id points = mesh.num_points();
  normals.resize(3 * points);
  auto* out = reinterpret_cast<Vec3f*>(normals.data());
  if (blocks) {
    // The three corners of a triangle share its face normal (arity 3).
    keyreduce::reduce_blocked(C, blocks->data(), static_cast<Id>(blocks->size()) - 1, 3, face_normal, add,
                              Vec3f{0, 0, 0}, out, points);
    parallel::for_each(points, [&](Id p) { out[p] = unit(out[p]); });
    return;
  }
  std::vector<Vec3f> face(mesh.num_cells());
  parallel::for_each(mesh.num_cells(), [&](Id t) { face[t] = face_normal(t); });
  keyreduce::reduce(
      groups, [&](Id pair) { return face[pair / 3]; }, add, [&](Vec3f sum, Id) { return unit(sum); }, out);
}

template <class K, class T>
SurfaceMesh contour_typed(const ImageGrid& grid, const T* samples, const ContourOptions& opt, ContourStats& st,
                          std::vector<std::uint64_t>* point_keys) {
  GridShape s = shape_of(grid);
  s.k_offset = opt.total_planes ? opt.first_plane : 0;
  const Id n_iso = static_cast<Id>(opt.isovalues.size());
  const K keys_per_iso = static_cast<K>(3 * s.n);
  const K key_range = static_cast<K>(n_iso) * keys_per_iso;
  st.key_bits = static_cast<int>(sizeof(K) * 8);
  const EdgeInterpolator<T> interp{samples, s, opt.isovalues.data(), static_cast<Id>(keys_per_iso)};
  const bool average = opt.normals == ContourNormals::Average;

  SurfaceMesh mesh;
  // One group per output point; groups.unique_keys[p] is the key of point p.
  // The pair order is built only for VERTEX-WELD with averaged normals.
  keyreduce::Groups<K> groups;
  InsideBits bits;
  std::vector<Id> blocks;  // slab blocks of the soup, for averaging
  {
    // The triangle soup: one key per triangle corner.
    std::vector<K> soup;
    for (Id iso_index = 0; iso_index < n_iso; ++iso_index) {
      auto t0 = Clock::now();
      classify(samples, s, InsideTest<T>(opt.isovalues[iso_index]), bits);
      st.classify += seconds_since(t0);
      generate_soup<K>(bits, s, opt.ghost_below, s.nz - 1 - opt.ghost_above, static_cast<K>(iso_index) * keys_per_iso,
                       soup, blocks, st);
    }
    const Id corners = static_cast<Id>(soup.size());
    blocks.push_back(corners);
    st.soup_points = corners;
    auto t0 = Clock::now();
    // KEY-REDUCE's groups are averaged by slab blocks and need no pair order.
    const auto order = keyreduce::Order::Skip;
    if (opt.weld == ContourWeld::KeyReduce || opt.weld == ContourWeld::KeyReduceSort) {
      groups = opt.weld == ContourWeld::KeyReduce
                   ? keyreduce::partition_dense(soup.data(), corners, key_range, order)
                   : keyreduce::partition_sort(soup.data(), corners, parallel::bits_needed<K>(key_range - 1), order);
      mesh.connectivity = std::move(groups.index_map);  // the index map is the triangle list
    } else {
      // VERTEX-WELD: the soup a plain marching cubes writes, a position per
      // corner, welded by coordinates.
      std::vector<float> soup_xyz(3 * corners);
      parallel::for_each(corners, [&](Id c) { interp.position(interp.locate(soup[c]), &soup_xyz[3 * c]); });
      weld::WeldResult welded = weld::vertex_weld(soup_xyz.data(), corners);
      mesh.points = std::move(welded.points);
      mesh.connectivity = std::move(welded.index_map);
      groups.unique_keys.resize(welded.first.size());
      parallel::for_each(groups.num_groups(), [&](Id p) { groups.unique_keys[p] = soup[welded.first[p]]; });
      if (average) {
        // Average over the coordinate-welded groups with KEY-REDUCE's reduction.
        groups.index_map = mesh.connectivity;
        keyreduce::build_order(groups);
      }
    }
    st.weld += seconds_since(t0);
  }
  bits.words = {};

  auto t0 = Clock::now();
  const Id points = groups.num_groups();
  const K* point_key = groups.unique_keys.data();
  if (point_keys) {
    // Global keys: the slab's edges renumbered as edges of the whole grid.
    const std::uint64_t local_per_iso = static_cast<std::uint64_t>(keys_per_iso);
    const std::uint64_t total_per_iso = 3ull * static_cast<std::uint64_t>(s.nxy) *
                                        static_cast<std::uint64_t>(opt.total_planes ? opt.total_planes : s.nz);
    const std::uint64_t shift = 3ull * static_cast<std::uint64_t>(s.nxy) * static_cast<std::uint64_t>(s.k_offset);
    point_keys->resize(static_cast<std::size_t>(points));
    parallel::for_each(points, [&](Id p) {
      const std::uint64_t k = point_key[p];
      (*point_keys)[p] = (k / local_per_iso) * total_per_iso + k % local_per_iso + shift;
    });
  }
  if (mesh.points.empty()) {
    mesh.points.resize(3 * points);
    parallel::for_each(points, [&](Id p) { interp.position(interp.locate(point_key[p]), &mesh.points[3 * p]); });
  }
  if (opt.scalars) {
    Field f{grid.name, 1, std::vector<float>(points)};
    parallel::for_each(points, [&](Id p) { f.values[p] = interp.scalar(interp.locate(point_key[p])); });
    mesh.point_fields.push_back(std::move(f));
  }
  if (opt.normals == ContourNormals::Gradient) {
    Field f{"Normals", 3, std::vector<float>(3 * points)};
    parallel::for_each(points, [&](Id p) { interp.gradient_normal(interp.locate(point_key[p]), &f.values[3 * p]); });
    mesh.point_fields.push_back(std::move(f));
  }
  if (opt.curvature) {
    Field f{"mean_curvature", 1, std::vector<float>(points)};
    parallel::for_each(points, [&](Id p) { f.values[p] = interp.mean_curvature(interp.locate(point_key[p])); });
    mesh.point_fields.push_back(std::move(f));
  }
  if (average && !opt.coarsen) {
    Field f{"Normals", 3, {}};
    average_normals(groups, opt.weld == ContourWeld::VertexWeld ? nullptr : &blocks, mesh, f.values);
    mesh.point_fields.push_back(std::move(f));
  }
  st.fields += seconds_since(t0);
  if (opt.coarsen) {
    t0 = Clock::now();
    // The coarse key: the edge's end point nearest to the crossing (the far
    // end from t = 0.5 on), per isovalue.
    std::vector<std::uint64_t> coarse(static_cast<std::size_t>(points));
    parallel::for_each(points, [&](Id p) {
      const auto e = interp.locate(point_key[p]);
      const Id iso_index = static_cast<Id>(static_cast<std::uint64_t>(point_key[p]) / static_cast<std::uint64_t>(keys_per_iso));
      coarse[p] = static_cast<std::uint64_t>(iso_index * s.n + e.p0 + (e.t >= 0.5 ? s.stride[e.axis] : 0));
    });
    st.triangles_before_coarsening = mesh.num_cells();
    mesh = coarsen(mesh, coarse, static_cast<std::uint64_t>(n_iso * s.n));
    if (average) generate::average_normals(mesh);
    st.coarsen += seconds_since(t0);
  }
  return mesh;
}

}  // namespace

SurfaceMesh contour(const ImageGrid& grid, const ContourOptions& options, ContourStats* stats,
                    std::vector<std::uint64_t>* point_keys) {
  if (options.isovalues.empty()) throw InputError("contour: no isovalue given");
  for (double iso : options.isovalues)
    if (!std::isfinite(iso)) throw InputError("contour: isovalue " + std::to_string(iso) + " is not finite");
  for (int a = 0; a < 3; ++a)
    if (grid.dims[a] < 2)
      throw InputError("contour: grid has " + std::to_string(grid.dims[a]) + " point(s) along axis " +
                       "xyz"[a] + std::string(" (need at least 2)"));
  if (static_cast<Id>(grid.byte_count()) != grid.num_points() * static_cast<Id>(scalar_size(grid.type)))
    throw InputError("contour: grid holds " + std::to_string(grid.byte_count()) + " bytes, dims need " +
                     std::to_string(grid.num_points() * static_cast<Id>(scalar_size(grid.type))));
  if (options.backend == Backend::Cuda) {
    if (point_keys || options.total_planes)
      throw InputError("--backend cuda: streamed (slab) contouring is not available on the GPU yet");
    return cuda::contour(grid, options, stats);
  }
  if (options.ghost_below < 0 || options.ghost_below > 1 || options.ghost_above < 0 || options.ghost_above > 1 ||
      ((options.ghost_below || options.ghost_above) && !options.total_planes) ||
      grid.dims[2] - options.ghost_below - options.ghost_above < 2)
    throw InputError("contour: ghost planes (" + std::to_string(options.ghost_below) + " below, " +
                     std::to_string(options.ghost_above) + " above) need a slab of at least two other planes");
  if ((options.ghost_below || options.ghost_above) && options.coarsen)
    throw InputError("contour: coarsening a slab with ghost planes is not supported");
  if (point_keys && options.coarsen)
    throw InputError("contour: coarsened points have no edge keys (streamed contouring does not coarsen yet)");
  if (options.total_planes && (options.first_plane < 0 || options.first_plane + grid.dims[2] > options.total_planes))
    throw InputError("contour: slab planes [" + std::to_string(options.first_plane) + ", " +
                     std::to_string(options.first_plane + grid.dims[2]) + ") lie outside the grid's " +
                     std::to_string(options.total_planes) + " planes");
  ContourStats local;
  ContourStats& st = stats ? *stats : local;
  st = ContourStats{};
  const std::uint64_t key_range = 3ull * static_cast<std::uint64_t>(grid.num_points()) * options.isovalues.size();
  return visit_scalars(grid, [&](const auto* samples) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(samples)>>;
    if (key_range <= std::numeric_limits<std::uint32_t>::max())
      return contour_typed<std::uint32_t, T>(grid, samples, options, st, point_keys);
    return contour_typed<std::uint64_t, T>(grid, samples, options, st, point_keys);
  });
}

std::vector<Id> triangles_per_layer(const ImageGrid& grid, const ContourOptions& options) {
  for (int a = 0; a < 3; ++a)
    if (grid.dims[a] < 2) throw InputError("triangles_per_layer: need at least 2 points along every axis");
  const auto& table = marching_cubes_table();
  return visit_scalars(grid, [&](const auto* samples) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(samples)>>;
    const GridShape s = shape_of(grid);
    std::vector<Id> per_row(static_cast<std::size_t>((s.ny - 1) * (s.nz - 1)), 0);
    InsideBits bits;
    for (double iso : options.isovalues) {
      classify(samples, s, InsideTest<T>(iso), bits);
      parallel::for_each_dynamic((s.ny - 1) * (s.nz - 1), [&](Id r) {
        Id count = 0;
        for_each_cut_voxel(bits, s, r % (s.ny - 1), r / (s.ny - 1),
                           [&](Id, unsigned cube_case) { count += table.triangle_count[cube_case]; });
        per_row[r] += count;
      }, 8);
    }
    std::vector<Id> layers(static_cast<std::size_t>(s.nz - 1), 0);
    for (Id r = 0; r < static_cast<Id>(per_row.size()); ++r) layers[r / (s.ny - 1)] += per_row[r];
    return layers;
  });
}

}  // namespace keymesh::generate
