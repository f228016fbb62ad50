#include "keymesh/generate/contour/contour.hpp"

#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

#include "keymesh/core/error.hpp"
#include "keymesh/core/free_storage.hpp"
#include "keymesh/core/progress.hpp"
#include "keymesh/core/work_estimate.hpp"
#include "keymesh/generate/coarsen/coarsen.hpp"
#include "keymesh/generate/coarsen/split_nonmanifold.hpp"
#include "keymesh/generate/contour/contour_kernels.hpp"
#include "keymesh/generate/contour/marching_cubes_table.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/keyreduce/reduce.hpp"
#include "keymesh/mesh/label_scalars.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"
#include "keymesh/keyreduce/weld.hpp"
#include "generate/coarsen/coarse_fans.hpp"
#include "generate/coarsen/contour_coarse_rows.hpp"
#include "contour_rows.hpp"
#include "derivative_rows.hpp"
#include "grid_lines.hpp"
#include "history_t.hpp"
#include "keymesh/generate/contour/layer_blocks.hpp"
#include "voxel_bits.hpp"

namespace keymesh::generate {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The table is the mirrored one when the caller reversed the axes.
GridShape shape_of(const ImageGrid& g, const ContourOptions& opt) {
  GridShape s{};
  s.table = &marching_cubes_table(opt.reversed_axes);
  s.reversed_axes = opt.reversed_axes;
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
  // Positions in the larger grid's indices: a slab's planes, a block's box.
  for (int a = 0; a < 3; ++a) s.offset[a] = opt.position_offset[a];
  if (opt.total_planes) s.offset[2] += opt.first_plane;
  return s;
}

// kSlabsPerBlock (layer_blocks.hpp): voxel slabs per block of the soup handed
// to keyreduce::reduce_blocked.


// One isovalue's triangle soup as edge keys, appended to `keys` with
// `key_offset` added (the isovalue's index times 3N). Appends to `blocks`
// the first pair of every kSlabsPerBlock voxel slabs: a point is shared only
// by the slabs on either side of its plane, so a block shares points with
// its two neighbours at most.
template <class K>
Id generate_soup(const InsideBits& bits, const GridShape& s, Id k_begin, Id k_end, K key_offset, std::vector<K>& keys,
                 std::vector<Id>& blocks, ContourStats& st) {
  // Voxel layers [k_begin, k_end): all of them but ghost planes' layers.
  const auto& table = *s.table;
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

// Point normals (mesh/normals.hpp): the area-weighted face normals summed
// from zero by KEY-REDUCE, then normalised. With `blocks` (slab blocks of
// the soup, see generate_soup) the sums are scattered block by block
// (keyreduce::reduce_blocked), with no pair order; otherwise (VERTEX-WELD's
// groups) summed over the groups' pair order. Both merge a point's corners
// in increasing corner order, from zero.
template <class K>
void average_normals(const keyreduce::Groups<K>* groups, const std::vector<Id>* blocks, const SurfaceMesh& mesh,
                     Array<float>& normals) {
  const Id points = mesh.num_points();
  normals.resize(3 * points);
  auto* out = reinterpret_cast<Vec3f*>(normals.data());
  if (blocks) {
    sum_blocked_normals(mesh, *blocks, out);  // layer_blocks.hpp: the order streamed and MPI runs repeat
  } else {
    sum_face_normals(*groups, face_normals(mesh).data(), out);
  }
  normalize(out, points);
}

// Where each point's values go: the mesh's arrays (null when not asked
// for), written at the point's id. One writer for both plans, so a point's
// bytes do not depend on how its id was found.
struct PointArrays {
  float* xyz = nullptr;
  float* scalar = nullptr;
  float* gradient_normal = nullptr;
  float* curvature = nullptr;
  float* history_t = nullptr;       // ContourOptions::history (history_t.hpp)
  std::uint64_t* key = nullptr;     // global edge key (point_keys)
  std::uint64_t* coarse = nullptr;  // coarse key: the edge's end nearest the crossing
};

// The derivatives at a cut edge's two ends (g at its first grid point and
// at its far end; h, derivatives_at's second derivatives, only when
// curvature is asked for), as its point's fields need them.
struct EdgeEnds {
  const double* g[2] = {};
  const double* h[2] = {};
};

template <class T>
struct PointWriter {
  const EdgeInterpolator<T>& interp;
  const GridShape& s;
  PointArrays out;
  std::uint64_t total_per_iso = 0;  // keys per isovalue of the whole grid (3 N_total)
  std::uint64_t key_shift = 0;      // 3 nxy * first plane: the slab's first key in the whole grid
  std::uint64_t points_per_iso = 0; // coarse keys per isovalue of the whole grid (N_total)
  std::uint64_t point_shift = 0;    // nxy * first plane: the slab's first grid point in the whole grid

  bool positions_and_scalar_only() const {
    return out.xyz && !out.gradient_normal && !out.curvature && !out.history_t && !out.key && !out.coarse;
  }
  bool needs_derivatives() const { return out.gradient_normal || out.curvature; }

  // Every field of the point, the derivatives at its edge's ends computed
  // here (the soup plans: their points come in key order across the whole
  // grid, with no rows to keep).
  void operator()(Id id, const typename EdgeInterpolator<T>::Point& p, Id iso_index) const {
    if (out.xyz) interp.position(p, out.xyz + 3 * id);
    double d[2][9];
    EdgeEnds ends;
    if (needs_derivatives()) {
      Id ijk1[3] = {p.ijk[0], p.ijk[1], p.ijk[2]};
      ++ijk1[p.axis];
      if (out.curvature) {
        interp.derivatives_at(p.p0, p.ijk, d[0], d[0] + 3);
        interp.derivatives_at(interp.far_end(p), ijk1, d[1], d[1] + 3);
        ends.h[0] = d[0] + 3, ends.h[1] = d[1] + 3;
      } else {
        interp.gradient_at(p.p0, p.ijk, d[0]);
        interp.gradient_at(interp.far_end(p), ijk1, d[1]);
      }
      ends.g[0] = d[0], ends.g[1] = d[1];
    }
    fields(id, p, iso_index, ends);
  }

  // Every field but the position, from the derivatives at the edge's ends
  // (derivatives_at's gradient is gradient_at's: the same bits either way);
  // with Hessians false, the caller has none (and no curvature to write).
  template <bool Hessians = true>
  [[gnu::always_inline]] void fields(Id id, const typename EdgeInterpolator<T>::Point& p, Id iso_index,
                                     const EdgeEnds& ends) const {
    if (out.scalar) out.scalar[id] = interp.scalar(p);
    if (out.gradient_normal) interp.gradient_normal(p, ends.g[0], ends.g[1], out.gradient_normal + 3 * id);
    if constexpr (Hessians)
      if (out.curvature) out.curvature[id] = interp.mean_curvature(p, ends.g[0], ends.h[0], ends.g[1], ends.h[1]);
    if (out.history_t) out.history_t[id] = history_t(s, p.axis, p.ijk[p.axis], p.t);
    if (out.key)
      out.key[id] = static_cast<std::uint64_t>(iso_index) * total_per_iso + 3 * static_cast<std::uint64_t>(p.p0) +
                    static_cast<std::uint64_t>(p.axis) + key_shift;
    if (out.coarse)
      out.coarse[id] = static_cast<std::uint64_t>(iso_index) * points_per_iso + point_shift +
                       static_cast<std::uint64_t>(interp.nearest_point(p));
  }
};

// The structured pass's point writer when gradient normals or curvature are
// asked for: PointWriter's fields, the derivatives at each edge's ends
// taken from the thread's DerivativeRows (computed once per grid point),
// the position from GridLines. write_rows copies it for each task, whose
// thread's rows it then holds: the row being written and the rows its y
// and z edges end in.
template <class T, bool Hessian>
struct RowPointWriter {
  using Rows = DerivativeRows<T, Hessian>;
  const PointWriter<T>& write;
  const GridLines& lines;
  Id iso;
  std::uint64_t pass;
  const InsideBits& bits;
  Rows* rows = nullptr;
  Id j = -1, k = -1;
  typename Rows::Row here{}, next_y{}, next_z{};
  [[gnu::always_inline]] void operator()(Id id, Id i, Id j_, Id k_, int axis) {
    const EdgeInterpolator<T>& interp = write.interp;
    const GridShape& s = interp.s;
    if (j_ != j || k_ != k) {
      if (!rows) rows = &Rows::of_this_thread(interp, pass);
      j = j_, k = k_;
      here = rows->row(j, k);
      if (j + 1 < s.ny) next_y = rows->row(j + 1, k);
      if (k + 1 < s.nz) next_z = rows->row(j, k + 1);
      if constexpr (!Hessian) {
        // Gradients: the three rows' edge ends computed before the row's
        // points (a superset: every point with a cut edge to a neighbour),
        // as a loop of independent computations. ch2better, contour_bench
        // 2 threads: 56-57 -> 52 ms, though 0.84 -> 0.94 G instructions; not
        // for derivatives_at (1.23 -> 1.29 G, no time won measured).
        here.compute_edge_ends(bits);
        if (j + 1 < s.ny) next_y.compute_edge_ends(bits);
        if (k + 1 < s.nz) next_z.compute_edge_ends(bits);
      }
    }
    const auto p = interp.at(i + j * s.nx + k * s.nxy, i, j, k, axis, iso);
    lines.position(p, write.out.xyz + 3 * id);
    const auto& far = axis == 0 ? here : (axis == 1 ? next_y : next_z);
    const Id far_i = axis == 0 ? i + 1 : i;
    const double* const d0 = Hessian ? here.at(i) : here.computed(i);
    const double* const d1 = Hessian ? far.at(far_i) : far.computed(far_i);
    EdgeEnds ends{{d0, d1}, {}};
    if constexpr (Hessian) ends.h[0] = d0 + 3, ends.h[1] = d1 + 3;
    write.template fields<Hessian>(id, p, iso, ends);
  }
};

// The mesh's point arrays, sized for `points` (with room for `room_after`
// more: the coarsening's split appends copies), and the writer filling them.
template <class T>
PointWriter<T> prepare_points(SurfaceMesh& mesh, Id points, const ImageGrid& grid, const EdgeInterpolator<T>& interp,
                              const GridShape& s, const ContourOptions& opt, std::vector<std::uint64_t>* point_keys,
                              std::vector<std::uint64_t>* nearest_keys, bool write_xyz, Id room_after = 0) {
  PointWriter<T> w{interp, s, {}, 0, 0, 0, 0};
  // Output arrays at their final size, unwritten (Array), with huge pages
  // asked for and their pages faulted in by the threads (a host process
  // such as Python has no huge pages by default).
  auto sized = [&](Array<float>& v, int components) {
    parallel::reserve_fresh(v, static_cast<std::size_t>(components * (points + room_after)));
    parallel::resize_fresh(v, static_cast<std::size_t>(components * points));
    return v.data();
  };
  mesh.point_fields.reserve(mesh.point_fields.size() + 4);  // the writer's pointers stay valid
  auto field = [&](const std::string& name, int components) {
    mesh.point_fields.push_back(Field{name, components, {}});
    return sized(mesh.point_fields.back().values, components);
  };
  if (write_xyz) w.out.xyz = sized(mesh.points, 3);
  if (opt.scalars) w.out.scalar = field(grid.name, 1);
  if (opt.normals == ContourNormals::Gradient) w.out.gradient_normal = field("Normals", 3);
  if (opt.curvature) w.out.curvature = field("mean_curvature", 1);
  if (opt.history) w.out.history_t = field("history_t", 1);
  // Global keys: the slab's edges and points renumbered as those of the whole grid.
  w.points_per_iso = static_cast<std::uint64_t>(s.nxy) * static_cast<std::uint64_t>(opt.total_planes ? opt.total_planes : s.nz);
  w.point_shift = static_cast<std::uint64_t>(s.nxy) * static_cast<std::uint64_t>(opt.total_planes ? opt.first_plane : 0);
  w.total_per_iso = 3 * w.points_per_iso;
  w.key_shift = 3 * w.point_shift;
  if (point_keys) {
    point_keys->resize(static_cast<std::size_t>(points));
    w.out.key = point_keys->data();
  }
  if (nearest_keys) {
    nearest_keys->resize(static_cast<std::size_t>(points));
    w.out.coarse = nearest_keys->data();
  }
  return w;
}

// Averaged normals (when asked for) and coarsening, after the points and
// triangles are written. `coarse` (the soup plans: each point's nearest grid
// point) coarsens the mesh here; the structured plan coarsened in its pass
// and passes null.
template <class K>
void finish_contour(SurfaceMesh& mesh, const ContourOptions& opt, const keyreduce::Groups<K>* vertex_weld_groups,
                    const std::vector<Id>& blocks, const std::vector<std::uint64_t>* coarse, std::uint64_t coarse_range,
                    ContourStats& st) {
  const bool average = opt.normals == ContourNormals::Average;
  if (average && !opt.coarsen) {
    progress::report("normals", 0.9);
    auto t0 = Clock::now();
    Field f{"Normals", 3, {}};
    average_normals(vertex_weld_groups, vertex_weld_groups ? nullptr : &blocks, mesh, f.values);
    mesh.point_fields.push_back(std::move(f));
    st.fields += seconds_since(t0);
  }
  if (!opt.coarsen) return;
  progress::report("coarsen", 0.9);
  auto t0 = Clock::now();
  if (coarse) {
    st.triangles_before_coarsening = mesh.num_cells();
    mesh = coarsen(mesh, *coarse, coarse_range);
  }
  if (average) keymesh::average_normals(mesh);
  st.coarsen += seconds_since(t0);
}

// A float as a float: GCC 12 (-O3, vectorised) may add the double a float
// was rounded from instead of the float itself, which changes the sum's
// last bits; coarsen() sums the stored floats, and so must the pass.
inline float as_stored(float v) {
  asm("" : "+x"(v));
  return v;
}

// Whether a cut edge's crossing is nearer its far end (its coarse point is
// the far end): EdgeInterpolator::at's t, clamped, >= 0.5. For 8-bit
// samples the answer for every pair of end samples, 64 K bits made by the
// same expression once per isovalue, is looked up instead of a division per
// cut edge.
template <class T>
class NearerFarEnd {
 public:
  explicit NearerFarEnd(double isovalue) : isovalue_(isovalue) {
    if constexpr (kTabulated)
      for (unsigned a = 0; a < 256; ++a)
        for (unsigned b = 0; b < 256; ++b)
          table_[(a << 8 | b) >> 6] |=
              std::uint64_t{computed(static_cast<double>(static_cast<T>(a)), static_cast<double>(static_cast<T>(b)))}
              << (b & 63u);
  }

  bool operator()(T v0, T v1) const {
    if constexpr (kTabulated) {
      const unsigned pair = static_cast<unsigned>(static_cast<std::uint8_t>(v0)) << 8 | static_cast<std::uint8_t>(v1);
      return ((table_[pair >> 6] >> (pair & 63u)) & 1u) != 0;
    } else {
      return computed(static_cast<double>(v0), static_cast<double>(v1));
    }
  }

 private:
  static constexpr bool kTabulated = sizeof(T) == 1;
  bool computed(double v0, double v1) const {
    const double t = (isovalue_ - v0) / (v1 - v0);
    return !std::isfinite(t) || t >= 0.5;
  }
  double isovalue_;
  std::array<std::uint64_t, kTabulated ? 1024 : 0> table_{};
};

// A coarse point's values: the mean of its crossings' values, each made as
// PointWriter makes the fine point (position, scalar, gradient normal,
// curvature), summed in double from +0 in edge-key order, as coarsen()
// averages a group; gradient normals renormalised, as coarsen() does. A
// grid row's coarse points at a time (CoarseRow): each crossing is computed
// once and added to its point's running sums, kept for the row in the
// thread's scratch (the crossings come code by code, which is key order for
// every point).
template <class T>
struct CoarsePointWriter {
  PointWriter<T> out;  // the mesh's arrays, at coarse ids
  GridLines lines;
  std::uint64_t pass = new_derivative_pass();

  explicit CoarsePointWriter(const PointWriter<T>& arrays) : out(arrays), lines(arrays.s) {}

  // Step 7 (contour_coarse_rows.hpp) for one isovalue: its every coarse point
  // written at its id.
  void write_points(const InsideBits& bits, const CoarseBits& cb, Id iso) const {
    auto rows = [&](auto scalar, auto normal, auto curvature) {
      for_each_coarse_row(
          bits, out.s, cb,
          [&](const CoarseRow& row) {
            fields<decltype(scalar)::value, decltype(normal)::value, decltype(curvature)::value>(row, iso);
          },
          out.interp.samples);
    };
    // The fields asked for, as template arguments.
    auto with_curvature = [&](auto scalar, auto normal) {
      if (out.out.curvature) rows(scalar, normal, std::true_type{});
      else rows(scalar, normal, std::false_type{});
    };
    auto with_normal = [&](auto scalar) {
      if (out.out.gradient_normal) with_curvature(scalar, std::true_type{});
      else with_curvature(scalar, std::false_type{});
    };
    if (out.out.scalar) with_normal(std::true_type{});
    else with_normal(std::false_type{});
  }

 private:
  // Running sums of a row's points, `per_point` doubles each, by i; in
  // the calling thread's scratch, all +0 (as a KEY-REDUCE's sum starts):
  // each writer sets the sums it read back to +0 as it writes the means,
  // so no pass zeroes them.
  static double* zeroed_sums(Id nx, int per_point) {
    thread_local std::vector<double> sums;
    if (static_cast<Id>(sums.size()) < per_point * nx) sums.resize(static_cast<std::size_t>(per_point * nx), 0.0);
    return sums.data();
  }

  // The point on crossing x of axis A: EdgeInterpolator::at, its first
  // grid point's index from x.
  template <int A>
  [[gnu::always_inline]] static typename EdgeInterpolator<T>::Point crossing(const EdgeInterpolator<T>& interp,
                                                                            const CoarseCrossing& x, Id iso) {
    const GridShape& s = interp.s;
    return interp.at(x.i + x.j * s.nx + x.k * s.nxy, x.i, x.j, x.k, A, iso);
  }

  // The fields asked for, each a sum (x, y, z, then the scalar, the
  // normal, the curvature) and a count, with no small array per crossing.
  // A crossing's two coordinates off its axis are its point's own grid
  // coordinates (GridLines, position()'s floats); only the one along its
  // axis is computed. The derivatives at a crossing's ends come from the
  // thread's DerivativeRows: a coarse point is one end of each of its
  // crossings, and a grid point ends the crossings of up to three rows.
  template <bool Scalar, bool Normal, bool Curvature>
  void fields(const CoarseRow& row, Id iso) const {
    constexpr int kScalar = 3, kNormal = kScalar + Scalar, kCurvature = kNormal + 3 * Normal;
    constexpr int kCount = kCurvature + Curvature, kPerPoint = (kCount + 2) / 2 * 2;  // aligned pairs
    constexpr bool kDerivatives = Normal || Curvature;
    using Rows = DerivativeRows<T, Curvature>;
    double* const sum = zeroed_sums(out.s.nx, kPerPoint);
    // Local copies, which the stores into the sums cannot alias (the
    // grid's doubles and the samples' pointer would be loaded again
    // after every store otherwise).
    const EdgeInterpolator<T> interp = out.interp;
    const GridShape& s = interp.s;
    const float* const gx = lines.line[0].data();
    const float gy = lines.line[1][row.j], gz = lines.line[2][row.k];
    // The derivative rows a crossing of the row ends in: the row's own,
    // and those above and below it along y and z (where it has crossings).
    [[maybe_unused]] typename Rows::Row here{}, below_y{}, above_y{}, below_z{}, above_z{};
    if constexpr (kDerivatives) {
      Rows& rows = Rows::of_this_thread(interp, pass);
      here = rows.row(row.j, row.k);
      if (row.far.y_below) below_y = rows.row(row.j - 1, row.k);
      if (row.cuts.next_y) above_y = rows.row(row.j + 1, row.k);
      if (row.far.z_below) below_z = rows.row(row.j, row.k - 1);
      if (row.cuts.next_z) above_z = rows.row(row.j, row.k + 1);
    }
    row.for_each_crossing([&](Id i, const CoarseCrossing& x, auto axis) __attribute__((always_inline)) {
      constexpr int a = decltype(axis)::value;
      const auto p = crossing<a>(interp, x, iso);
      float xyz[3] = {gx[i], gy, gz};
      xyz[a] = grid_coordinate(s, a, p.ijk[a], p.t);
      // Every value made before the first store: 8-bit samples may alias
      // anything stored, and would be read again.
      [[maybe_unused]] float v = 0, n[3] = {}, c = 0;
      if constexpr (Scalar) v = interp.scalar(p);
      if constexpr (kDerivatives) {
        // The crossing's first grid point and far end: along x both in the
        // row; along y (z) the edge comes from the row below or leaves for
        // the row above.
        const double *d0, *d1;
        if constexpr (a == 0) {
          d0 = here.at(x.i), d1 = here.at(x.i + 1);
        } else {
          const bool from_below = a == 1 ? x.j != row.j : x.k != row.k;
          const auto& below = a == 1 ? below_y : below_z;
          const auto& above = a == 1 ? above_y : above_z;
          d0 = (from_below ? below : here).at(x.i);
          d1 = (from_below ? here : above).at(x.i);
        }
        if constexpr (Normal) interp.gradient_normal(p, d0, d1, n);
        if constexpr (Curvature) c = interp.mean_curvature(p, d0, d0 + 3, d1, d1 + 3);
      }
      double* const acc = sum + kPerPoint * i;
      acc[0] += as_stored(xyz[0]), acc[1] += as_stored(xyz[1]), acc[2] += as_stored(xyz[2]);
      if constexpr (Scalar) acc[kScalar] += as_stored(v);
      if constexpr (Normal)
        acc[kNormal] += as_stored(n[0]), acc[kNormal + 1] += as_stored(n[1]), acc[kNormal + 2] += as_stored(n[2]);
      if constexpr (Curvature) acc[kCurvature] += as_stored(c);
      acc[kCount] += 1;
    });
    float* const xyz = out.out.xyz;
    row.for_each_point([&](Id i, std::uint32_t id) {
      double* const acc = sum + kPerPoint * i;
      const double count = acc[kCount];
      float* const o = xyz + 3 * std::size_t{id};
      o[0] = static_cast<float>(acc[0] / count), o[1] = static_cast<float>(acc[1] / count),
      o[2] = static_cast<float>(acc[2] / count);
      if constexpr (Scalar) out.out.scalar[id] = static_cast<float>(acc[kScalar] / count);
      if constexpr (Normal) {
        // Renormalised in float, as coarsen() does its mean.
        float v[3];
        for (int a = 0; a < 3; ++a) v[a] = static_cast<float>(acc[kNormal + a] / count);
        const float l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (l > 0) v[0] /= l, v[1] /= l, v[2] /= l;
        for (int a = 0; a < 3; ++a) out.out.gradient_normal[3 * std::size_t{id} + a] = v[a];
      }
      if constexpr (Curvature) out.out.curvature[id] = static_cast<float>(acc[kCurvature] / count);
      std::fill_n(acc, kPerPoint, 0.0);
    });
  }
};

// The structured plan's output arrays (below).
template <class T>
PointWriter<T> structured_outputs(SurfaceMesh& mesh, Id points, Id triangles, const ImageGrid& grid,
                                  const EdgeInterpolator<T>& interp, const GridShape& s, const ContourOptions& opt,
                                  std::vector<std::uint64_t>* point_keys, std::vector<std::uint64_t>* nearest_keys,
                                  PointIndex*& connectivity, Id room_after = 0);

void check_output_size(const ContourOptions& opt, Id points, Id triangles);

// Coarsening in the structured plan's pass (contour_coarse_rows.hpp): for
// every isovalue, rank the coarse points and count the coarse triangles
// kept (folds removed in that pass by remove_folds' rule), so that the
// outputs are allocated once at their final size; then write each coarse
// point as the mean of its crossings (the fine point values, as PointWriter
// makes them, summed in double in key order, as coarsen() sums a group) and
// the triangles with coarse ids, each once at its final place.
template <class T>
void coarsen_rows(SurfaceMesh& mesh, const std::vector<InsideBits>& bits, const std::vector<RowCounts>& rows,
                  Id fine_points, const ImageGrid& grid, const EdgeInterpolator<T>& interp,
                  const GridShape& s, const ContourOptions& opt, ContourStats& st) {
  const Id n_iso = static_cast<Id>(opt.isovalues.size());
  // Scratch kept by the calling thread, like the inside bits: every
  // isovalue's coarse points and face triangles.
  thread_local std::vector<CoarseBits> coarse;
  thread_local std::vector<CoarseTriangles> triangles;
  coarse.resize(static_cast<std::size_t>(n_iso));
  triangles.resize(static_cast<std::size_t>(n_iso));
  struct Release {
    ~Release() {
      std::size_t bytes = 0;
      for (const auto& c : coarse)
        bytes += (c.far.size + c.points.size) * sizeof(std::uint64_t) + c.first.size * sizeof(std::uint32_t);
      for (const auto& t : triangles) {
        for (const auto& f : t.faces) bytes += f.size * sizeof(FaceTriangle);
        for (const auto& e : t.entries) bytes += e.size * sizeof(std::uint16_t);
        for (const auto& v : t.voxel_i) bytes += v.size * sizeof(std::uint32_t);
      }
      if (bytes > kKeepScratchBytes) free_storage(coarse), free_storage(triangles);
    }
  } release;
  Id coarse_points = 0, coarse_triangles = 0, fine_triangles = 0, most_copies = 0;
  CoarseFans fans;
  NonmanifoldSuspects suspects;  // every isovalue's, ascending
  for (Id iso = 0; iso < n_iso; ++iso) {
    auto t0 = Clock::now();
    const NearerFarEnd<T> far_end(opt.isovalues[iso]);
    mark_coarse_points(bits[iso], s, rows[iso], interp.samples, far_end, coarse[iso]);
    st.weld += seconds_since(t0);
    t0 = Clock::now();
    tally_coarse_triangles(bits[iso], s, coarse[iso], triangles[iso]);
    fine_triangles += triangles[iso].fine_triangles;
    st.generate += seconds_since(t0);
    t0 = Clock::now();
    fold_and_count(s, coarse_triangles, triangles[iso]);
    coarse_triangles += triangles[iso].count;
    check_coarse_fans(s, triangles[iso], coarse[iso], fans);
    most_copies += fans.most_copies();
    st.coarsen += seconds_since(t0);
    t0 = Clock::now();
    number_coarse_points(s, coarse_points, coarse[iso]);
    coarse_points += coarse[iso].count;
    const std::vector<PointIndex> ids = suspect_ids(fans, coarse[iso]);
    suspects.points.insert(suspects.points.end(), ids.begin(), ids.end());
    suspect_triangles(s, fans, triangles[iso], suspects.triangles);
    st.weld += seconds_since(t0);
  }
  // The fine mesh's counts bound the coarsened one's (refused by name before
  // the outputs are allocated, as the plain contour's are).
  st.soup_points = 3 * fine_triangles;
  check_output_size(opt, fine_points, fine_triangles);
  auto t0 = Clock::now();
  PointIndex* connectivity = nullptr;
  // Room after the points for the split's copies, up to a sixteenth more
  // (a bound far past what it makes is not worth its pages; the split
  // grows the arrays when the room is short).
  const CoarsePointWriter<T> write{structured_outputs(mesh, coarse_points, coarse_triangles, grid, interp, s, opt,
                                                      nullptr, nullptr, connectivity,
                                                      std::min(most_copies, coarse_points / 16))};
  st.fields += seconds_since(t0);
  for (Id iso = 0; iso < n_iso; ++iso) {
    const CoarseBits& cb = coarse[iso];
    t0 = Clock::now();
    write.write_points(bits[iso], cb, iso);
    st.fields += seconds_since(t0);
    t0 = Clock::now();
    write_coarse_triangles(s, cb, triangles[iso], connectivity);
    st.generate += seconds_since(t0);
  }
  st.triangles_before_coarsening = fine_triangles;
  t0 = Clock::now();
  merge_ranges(suspects.triangles);
  split_nonmanifold(mesh, suspects);
  st.coarsen += seconds_since(t0);
}

// The structured plan's output, refused by name before it is allocated:
// past --max-memory (floats per point: position, scalar, normals, curvature;
// 3 ids per triangle; the fine counts bound a coarsened output) or past
// 32-bit corner ids.
void check_output_size(const ContourOptions& opt, Id points, Id triangles) {
  if (opt.max_output_bytes) {
    const std::uint64_t per_point = 4 * (3 + (opt.scalars ? 1 : 0) + (opt.normals != ContourNormals::None ? 3 : 0) +
                                         (opt.curvature ? 1 : 0));
    const auto p = static_cast<std::uint64_t>(points), t = static_cast<std::uint64_t>(triangles);
    check_work({p, t, saturating_add(saturating_mul(p, per_point), saturating_mul(t, 12))}, opt.max_output_bytes,
               "contour");
  }
  if (3 * triangles > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("contour: " + std::to_string(triangles) +
                     " triangles exceed the supported 1431655765 (2^32 - 1 corners)");
}

// The structured plan's output arrays, for `points` points and `triangles`
// triangles (the mesh's point arrays with room for `room_after` points
// more), and the writer filling them; `connectivity` is set to the
// triangles' array. The caller's (ContourOptions::output_arrays: positions
// and the scalar only, as contour() checked), or the mesh's: unwritten
// Arrays whose pages the threads fault in, so the contour writes each byte
// once, as it does the caller's.
template <class T>
PointWriter<T> structured_outputs(SurfaceMesh& mesh, Id points, Id triangles, const ImageGrid& grid,
                                  const EdgeInterpolator<T>& interp, const GridShape& s, const ContourOptions& opt,
                                  std::vector<std::uint64_t>* point_keys, std::vector<std::uint64_t>* nearest_keys,
                                  PointIndex*& connectivity, Id room_after) {
  if (opt.output_arrays) {
    const ContourArrays out = opt.output_arrays(points, triangles);
    connectivity = out.connectivity;
    PointWriter<T> w{interp, s, {}, 0, 0, 0, 0};
    w.out.xyz = out.points;
    if (opt.scalars) w.out.scalar = out.scalars;
    return w;
  }
  parallel::resize_fresh(mesh.connectivity, static_cast<std::size_t>(3 * triangles));
  connectivity = mesh.connectivity.data();
  return prepare_points(mesh, points, grid, interp, s, opt, point_keys, nearest_keys, true, room_after);
}

// The structured plan's pass over the rows of every isovalue (write_rows):
// the triangles, and the points with the writer that fits the fields asked
// for. Positions, with or without the scalar (the usual calls), get a
// writer of their own, inlined into the pass: position() by grid lines, and
// PointWriter's scalar(), so the same bytes; gradient normals and curvature
// take the derivatives at grid points from DerivativeRows (RowPointWriter).
template <class T>
void write_triangles_and_points(const std::vector<InsideBits>& bits, const std::vector<RowCounts>& rows,
                                const GridShape& s, Id kb, Id ke, const EdgeInterpolator<T>& interp,
                                const PointWriter<T>& write, PointIndex* connectivity) {
  const Id n_iso = static_cast<Id>(bits.size());
  auto pass = [&](auto&& write_point) {
    for (Id iso = 0; iso < n_iso; ++iso)
      write_rows(bits[iso], s, kb, ke, rows[iso], connectivity, [&](Id id, Id i, Id j, Id k, int axis) {
        write_point(id, interp.at(i + j * s.nx + k * s.nxy, i, j, k, axis, iso), iso);
      });
  };
  const GridLines lines(s);
  auto inlined = [&](auto with_scalar) {
    pass([&](Id id, const typename EdgeInterpolator<T>::Point& p, Id) {
      lines.position(p, write.out.xyz + 3 * id);
      if constexpr (decltype(with_scalar)::value) write.out.scalar[id] = interp.scalar(p);
    });
  };
  auto by_rows = [&](auto hessian) {
    const std::uint64_t pass_id = new_derivative_pass();
    for (Id iso = 0; iso < n_iso; ++iso)
      write_rows(bits[iso], s, kb, ke, rows[iso], connectivity,
                 RowPointWriter<T, decltype(hessian)::value>{write, lines, iso, pass_id, bits[iso]});
  };
  if (write.out.curvature) by_rows(std::true_type{});
  else if (write.needs_derivatives()) by_rows(std::false_type{});
  else if (!write.positions_and_scalar_only()) pass(write);
  else if (write.out.scalar) inlined(std::true_type{});
  else inlined(std::false_type{});
}

// The structured plan (contour_rows.hpp): classify every isovalue, count and
// scan rows, then write points and triangles at their final ids. No soup.
template <class T>
SurfaceMesh contour_rows(const ImageGrid& grid, const T* samples, const ContourOptions& opt, ContourStats& st,
                         std::vector<std::uint64_t>* point_keys, std::vector<std::uint64_t>* nearest_keys) {
  GridShape s = shape_of(grid, opt);
  const Id n_iso = static_cast<Id>(opt.isovalues.size());
  const EdgeInterpolator<T> interp{samples, s, opt.isovalues.data(), 3 * s.n};
  const Id kb = opt.ghost_below, ke = s.nz - 1 - opt.ghost_above;
  st.key_bits = 3 * s.n * n_iso <= Id{std::numeric_limits<std::uint32_t>::max()} ? 32 : 64;

  // Scratch kept by the calling thread across calls (a session contouring
  // one volume after another, e.g. from Python, reuses mapped memory instead
  // of faulting in fresh pages), released when it grows past kKeepScratchBytes.
  thread_local std::vector<InsideBits> bits;
  thread_local std::vector<RowCounts> rows;
  bits.resize(static_cast<std::size_t>(n_iso));
  rows.resize(static_cast<std::size_t>(n_iso));
  struct Release {
    ~Release() {
      std::size_t bytes = 0;
      for (const auto& b : bits) bytes += b.words.capacity() * sizeof(std::uint64_t);
      for (const auto& r : rows)
        for (const auto& c : r.brick_cases) bytes += c.cases.size;
      if (bytes > kKeepScratchBytes) std::vector<InsideBits>().swap(bits), std::vector<RowCounts>().swap(rows);
    }
  } release;
  std::vector<Id> blocks;  // slab blocks of the triangles, for averaging
  Id points = 0, triangles = 0;
  for (Id iso = 0; iso < n_iso; ++iso) {
    progress::report("classify", 0.4 * static_cast<double>(iso) / static_cast<double>(n_iso));
    auto t0 = Clock::now();
    classify(samples, s, InsideTest<T>(opt.isovalues[iso]), bits[iso]);
    st.classify += seconds_since(t0);
    t0 = Clock::now();
    const RowCounts& rc = rows[iso];
    if (opt.coarsen) {
      // The coarse pass walks the voxels itself (tally_coarse_triangles).
      count_grid_rows(bits[iso], s, kb, ke, points, rows[iso]);
      points = rc.point_first.back();
      st.weld += seconds_since(t0);
      continue;
    }
    count_rows(bits[iso], s, kb, ke, points, triangles, rows[iso]);
    for (Id k = 0; k < ke - kb; k += kSlabsPerBlock) blocks.push_back(3 * rc.triangle_first[k * (s.ny - 1)]);
    points = rc.point_first.back();
    triangles = rc.triangle_first.back();
    st.weld += seconds_since(t0);
  }

  SurfaceMesh mesh;
  progress::report("triangles", 0.4);
  if (opt.coarsen) {
    coarsen_rows(mesh, bits, rows, points, grid, interp, s, opt, st);
    finish_contour<std::uint32_t>(mesh, opt, nullptr, blocks, nullptr, 0, st);
    return mesh;
  }
  blocks.push_back(3 * triangles);
  st.soup_points = 3 * triangles;
  check_output_size(opt, points, triangles);
  auto t0 = Clock::now();
  progress::report("points", 0.5);
  PointIndex* connectivity = nullptr;
  const PointWriter<T> write =
      structured_outputs(mesh, points, triangles, grid, interp, s, opt, point_keys, nearest_keys, connectivity);
  // Triangles and points in one pass over the rows (st.generate holds both).
  write_triangles_and_points(bits, rows, s, kb, ke, interp, write, connectivity);
  st.generate += seconds_since(t0);
  finish_contour<std::uint32_t>(mesh, opt, nullptr, blocks, nullptr, 0, st);
  return mesh;
}

// The soup plans: every triangle corner written as its edge key, then
// grouped by KEY-REDUCE's sort plan, or by coordinates (VERTEX-WELD).
template <class K, class T>
SurfaceMesh contour_soup(const ImageGrid& grid, const T* samples, const ContourOptions& opt, ContourStats& st,
                         std::vector<std::uint64_t>* point_keys, std::vector<std::uint64_t>* nearest_keys) {
  GridShape s = shape_of(grid, opt);
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
      progress::report("soup", 0.3 * static_cast<double>(iso_index) / static_cast<double>(n_iso));
      auto t0 = Clock::now();
      classify(samples, s, InsideTest<T>(opt.isovalues[iso_index]), bits);
      st.classify += seconds_since(t0);
      generate_soup<K>(bits, s, opt.ghost_below, s.nz - 1 - opt.ghost_above, static_cast<K>(iso_index) * keys_per_iso,
                       soup, blocks, st);
    }
    const Id corners = static_cast<Id>(soup.size());
    blocks.push_back(corners);
    st.soup_points = corners;
    progress::report("weld", 0.3);
    auto t0 = Clock::now();
    // VERTEX-WELD welds the soup a plain marching cubes writes, a position
    // per corner, by coordinates; its groups are averaged with KEY-REDUCE's
    // ordered reduction (they have no slab blocks).
    const bool by_position = opt.weld == ContourWeld::VertexWeld;
    keyreduce::WeldSpec<K> spec;
    spec.plan = by_position ? keyreduce::WeldPlan::ByPosition : keyreduce::WeldPlan::Sort;
    spec.key_bits = parallel::bits_needed<K>(key_range - 1);
    spec.order = by_position && average ? keyreduce::Order::Build : keyreduce::Order::Skip;
    groups = keyreduce::weld(
        soup.data(), corners, spec, [&](Id c, float* xyz) { interp.position(interp.locate(soup[c]), xyz); },
        {by_position ? &mesh.points : nullptr, nullptr});
    // The index map is the triangle list.
    mesh.connectivity = spec.order == keyreduce::Order::Build ? groups.index_map : std::move(groups.index_map);
    st.weld += seconds_since(t0);
  }
  free_storage(bits.words);

  progress::report("points", 0.7);
  auto t0 = Clock::now();
  const Id points = groups.num_groups();
  const K* point_key = groups.unique_keys.data();
  std::vector<std::uint64_t> coarse;
  if (opt.coarsen) nearest_keys = &coarse;
  const bool welded_by_position = !mesh.points.empty() || points == 0;
  const PointWriter<T> write = prepare_points(mesh, points, grid, interp, s, opt, point_keys, nearest_keys,
                                              !welded_by_position);
  parallel::for_each(points, [&](Id p) {
    const std::uint64_t key = point_key[p];
    const Id iso_index = static_cast<Id>(key / static_cast<std::uint64_t>(keys_per_iso));
    write(p, interp.locate(key), iso_index);
  });
  st.fields += seconds_since(t0);
  const bool vertex_weld = opt.weld == ContourWeld::VertexWeld;
  finish_contour<K>(mesh, opt, vertex_weld ? &groups : nullptr, blocks, &coarse,
                    static_cast<std::uint64_t>(n_iso) * write.points_per_iso, st);
  return mesh;
}

}  // namespace

void check_contour_output(const ContourOptions& options, Id points, Id triangles) {
  check_output_size(options, points, triangles);
}

void check_contour_input(const ImageGrid& grid, const ContourOptions& options) {
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
}

SurfaceMesh contour(const ImageGrid& grid, const ContourOptions& options, ContourStats* stats,
                    std::vector<std::uint64_t>* point_keys, std::vector<std::uint64_t>* nearest_keys) {
  check_contour_input(grid, options);
  // The GPU is reached through keymesh/backend/contour.hpp (the layer above generate and cuda).
  if (options.backend != Backend::Cpu)
    throw InputError("--backend cuda: generate::contour runs on the CPU (backend::contour chooses the GPU)");
  if (options.ghost_below < 0 || options.ghost_below > 1 || options.ghost_above < 0 || options.ghost_above > 1 ||
      ((options.ghost_below || options.ghost_above) && !options.total_planes) ||
      grid.dims[2] - options.ghost_below - options.ghost_above < 2)
    throw InputError("contour: ghost planes (" + std::to_string(options.ghost_below) + " below, " +
                     std::to_string(options.ghost_above) + " above) need a slab of at least two other planes");
  if ((options.ghost_below || options.ghost_above) && options.coarsen)
    throw InputError("contour: coarsening a slab with ghost planes is not supported");
  if (options.output_arrays &&
      (options.weld != ContourWeld::KeyReduce || options.normals != ContourNormals::None || options.curvature ||
       options.coarsen || options.history || point_keys || nearest_keys))
    throw InputError("contour: output arrays are written by the structured plan (weld keyreduce) with no "
                     "normals, curvature, coarsening, history or keys");
  if (options.history && options.coarsen)
    throw InputError("contour: --history with --coarsen: a coarsened point merges crossings of several edges, "
                     "so it has no one edge and t (docs/HISTORY.md)");
  if ((point_keys || nearest_keys) && options.coarsen)
    throw InputError("contour: coarsened points have no edge keys (a slab's fine points and their nearest grid "
                     "points are merged, then coarsened, by the caller)");
  if (options.total_planes && (options.first_plane < 0 || options.first_plane + grid.dims[2] > options.total_planes))
    throw InputError("contour: slab planes [" + std::to_string(options.first_plane) + ", " +
                     std::to_string(options.first_plane + grid.dims[2]) + ") lie outside the grid's " +
                     std::to_string(options.total_planes) + " planes");
  ContourStats local;
  ContourStats& st = stats ? *stats : local;
  st = ContourStats{};
  const std::uint64_t key_range = 3ull * static_cast<std::uint64_t>(grid.num_points()) * options.isovalues.size();
  if (!is_grid_scalar(grid.type)) throw InputError("contour: " + wide_samples_refusal(grid.type));
  return visit_scalars(grid, [&](const auto* samples) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(samples)>>;
    if (options.weld == ContourWeld::KeyReduce) return contour_rows<T>(grid, samples, options, st, point_keys, nearest_keys);
    if (key_range <= std::numeric_limits<std::uint32_t>::max())
      return contour_soup<std::uint32_t, T>(grid, samples, options, st, point_keys, nearest_keys);
    return contour_soup<std::uint64_t, T>(grid, samples, options, st, point_keys, nearest_keys);
  });
}

std::vector<Id> triangles_per_layer(const ImageGrid& grid, const ContourOptions& options) {
  for (int a = 0; a < 3; ++a)
    if (grid.dims[a] < 2) throw InputError("triangles_per_layer: need at least 2 points along every axis");
  return visit_scalars(grid, [&](const auto* samples) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(samples)>>;
    const GridShape s = shape_of(grid, options);
    const auto& table = *s.table;
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
