#include "keymesh/generate/contour/contour_stream.hpp"

#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/core/free_storage.hpp"
#include "keymesh/core/retained_blocks.hpp"
#include "generate/coarsen/coarsen_slabs.hpp"
#include "keymesh/generate/contour/contour_kernels.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/mesh/normals.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/generate/contour/layer_blocks.hpp"

namespace keymesh::generate {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// What the streamed contour cannot do (yet), refused by name.
void check_streamable(const ImageGrid& head, const ContourOptions& options) {
  if (options.backend != Backend::Cpu) throw InputError("contour --memory-limit: streaming runs on the CPU backend");
  if (options.weld == ContourWeld::VertexWeld)
    throw InputError("contour --memory-limit: VERTEX-WELD has no keys to merge slabs by; use --weld keyreduce");
  if (options.history && options.coarsen)
    throw InputError("contour: --history with --coarsen: a coarsened point merges crossings of several edges, "
                     "so it has no one edge and t (docs/HISTORY.md)");
  for (int a = 0; a < 3; ++a)
    if (head.dims[a] < 2)
      throw InputError("contour: grid has " + std::to_string(head.dims[a]) + " point(s) along axis " + "xyz"[a] +
                       " (need at least 2)");
}

// Planes per slab (ghosts excluded) that `memory_limit` bytes hold.
Id planes_per_slab(const ImageGrid& head, std::size_t memory_limit, bool ghosts) {
  const Id nx = head.dims[0], ny = head.dims[1];
  const std::size_t plane_bytes = static_cast<std::size_t>(nx * ny) * scalar_size(head.type);
  const Id ghost_planes = ghosts ? 2 : 0;
  const Id fit = static_cast<Id>(memory_limit / plane_bytes);
  if (fit < 2 + ghost_planes)
    throw LimitError("contour --memory-limit " + std::to_string(memory_limit) + " bytes holds fewer than " +
                     std::string(ghosts ? "four " : "two ") + std::to_string(nx) + " x " + std::to_string(ny) +
                     " planes (" + std::to_string((2 + ghost_planes) * plane_bytes) + " bytes needed" +
                     (ghosts ? ", two of them ghost planes for the derivatives" : "") + ")");
  return std::min(fit - ghost_planes, head.dims[2]);
}

// Every slab's points (global keys, positions, fields), one after the
// other, and its triangles as indices into that list, per isovalue so that
// the isovalues' triangles end up one after the other, as in one contour.
// Averaged normals: summed over the merged mesh in the blocks of voxel
// layers one in-memory contour uses (layer_blocks.hpp), read from the
// points' edge keys, so they are its normals bit for bit (adding the slabs'
// partial sums would associate a shared point's additions differently).
struct SlabPoints {
  std::uint64_t per_iso;
  bool average;
  std::vector<std::uint64_t> keys;
  std::vector<std::uint64_t> nearest;  // each point's nearest grid point, when the slabs gave them
  std::vector<float> points;
  std::vector<Field> fields;  // every point field of the slabs, concatenated
  std::vector<std::vector<std::uint32_t>> corners;  // per isovalue
  LayerGrid layers;                                  // for the averaged normals' blocks

  void append(const SurfaceMesh& m, const std::vector<std::uint64_t>& slab_keys,
              const std::vector<std::uint64_t>& slab_nearest) {
    const std::uint64_t base = keys.size();
    if (base + slab_keys.size() > std::numeric_limits<std::uint32_t>::max())
      throw LimitError("contour --memory-limit: more than 2^32 - 1 points before merging");
    keys.insert(keys.end(), slab_keys.begin(), slab_keys.end());
    nearest.insert(nearest.end(), slab_nearest.begin(), slab_nearest.end());
    points.insert(points.end(), m.points.begin(), m.points.end());
    if (fields.empty())
      for (const Field& f : m.point_fields) fields.push_back(Field{f.name, f.components, {}});
    for (std::size_t i = 0; i < fields.size(); ++i)
      fields[i].values.insert(fields[i].values.end(), m.point_fields[i].values.begin(), m.point_fields[i].values.end());
    for (Id t = 0; t < m.num_cells(); ++t) {
      auto& dst = corners[static_cast<std::size_t>(slab_keys[m.connectivity[3 * t]] / per_iso)];
      for (int c = 0; c < 3; ++c) dst.push_back(static_cast<std::uint32_t>(base + m.connectivity[3 * t + c]));
    }
  }

  // KEY-REDUCE over the slabs' points: a shared plane's points appear
  // twice, with equal bits; the first of each group stands for it, and the
  // index map takes every slab point to its merged point. `merged_keys`
  // and `merged_nearest`, when given, receive the merged points' edge keys
  // and nearest grid points.
  SurfaceMesh merge(std::vector<std::uint64_t>* merged_keys, std::vector<std::uint64_t>* merged_nearest) const {
    const Id n = static_cast<Id>(keys.size());
    const auto g = keyreduce::partition_sort(keys.data(), n,
                                             parallel::bits_needed<std::uint64_t>(per_iso * corners.size() - 1),
                                             keyreduce::Order::Build);
    SurfaceMesh mesh;
    const Id unique = g.num_groups();
    mesh.points.resize(static_cast<std::size_t>(3 * unique));
    for (const Field& f : fields)
      mesh.point_fields.push_back(Field{f.name, f.components, Array<float>(static_cast<std::size_t>(unique * f.components))});
    std::vector<std::uint64_t> point_keys(average || merged_keys ? static_cast<std::size_t>(unique) : 0);
    if (merged_nearest) merged_nearest->resize(static_cast<std::size_t>(unique));
    parallel::for_each(unique, [&](Id p) {
      const Id first = g.order[g.offsets[p]];
      if (merged_nearest) (*merged_nearest)[p] = nearest[first];
      if (!point_keys.empty()) point_keys[p] = keys[first];
      for (int x = 0; x < 3; ++x) mesh.points[3 * p + x] = points[3 * first + x];
      for (std::size_t i = 0; i < fields.size(); ++i) {
        const int c = fields[i].components;
        std::copy_n(fields[i].values.begin() + c * first, c, mesh.point_fields[i].values.begin() + c * p);
      }
    });
    std::size_t total_corners = 0;
    for (const auto& c : corners) total_corners += c.size();
    mesh.connectivity.resize(total_corners);
    std::size_t at = 0;
    for (const auto& c : corners) {
      parallel::for_each(static_cast<Id>(c.size()), [&](Id i) { mesh.connectivity[at + i] = g.index_map[c[i]]; });
      at += c.size();
    }
    if (average) mesh.point_fields.push_back(blocked_average_normals(mesh, layer_blocks(mesh, point_keys, layers)));
    if (merged_keys) *merged_keys = std::move(point_keys);
    return mesh;
  }
};

void add_stats(ContourStats& total, const ContourStats& st) {
  total.classify += st.classify, total.generate += st.generate, total.weld += st.weld, total.fields += st.fields;
  total.soup_points += st.soup_points;
  total.key_bits = st.key_bits;
}

// Which planes to stream, [lo, hi] of the whole grid, and whether each
// fine point's nearest grid point is wanted.
struct PlaneWindow {
  Id lo, hi;
  bool nearest;
};

// The slabs of `window` read and contoured one after the other (global
// keys; ghost planes outside the window where the grid has them), each
// handed to `take(mesh, keys, nearest, k0, k_last, last)`.
template <class Take>
void for_each_slab(PlaneSource& source, const ContourOptions& options, std::size_t memory_limit, PlaneWindow window,
                   StreamStats& ss, ContourStats& total, Take take) {
  const ImageGrid& head = source.header();
  const Id nx = head.dims[0], ny = head.dims[1], nz = head.dims[2];
  // Gradient normals and curvature take central differences across a
  // slab's border: each slab reads a ghost plane on either side.
  const bool ghosts = options.normals == ContourNormals::Gradient || options.curvature;
  const Id planes = planes_per_slab(head, memory_limit, ghosts);
  ss.planes_per_slab = planes;
  ss.slab_bytes = static_cast<std::size_t>(std::min(planes + (ghosts ? 2 : 0), nz)) *
                  static_cast<std::size_t>(nx * ny) * scalar_size(head.type);
  ImageGrid slab;
  slab.spacing = head.spacing;
  slab.origin = head.origin;
  slab.name = head.name;
  ContourOptions opt = options;
  opt.total_planes = nz;
  opt.coarsen = false;
  if (options.normals == ContourNormals::Average) opt.normals = ContourNormals::None;  // summed after the slabs
  for (Id k0 = window.lo; k0 < window.hi; k0 += planes - 1) {
    const Id count = std::min(planes, window.hi + 1 - k0);
    const Id below = ghosts && k0 > 0 ? 1 : 0, above = ghosts && k0 + count < nz ? 1 : 0;
    auto t0 = Clock::now();
    slab.allocate({nx, ny, below + count + above}, head.type);
    source.read_planes(k0 - below, below + count + above, slab.bytes.data());
    ss.read += seconds_since(t0);
    t0 = Clock::now();
    opt.first_plane = k0 - below;
    opt.ghost_below = below;
    opt.ghost_above = above;
    std::vector<std::uint64_t> slab_keys, slab_nearest;
    ContourStats st;
    const SurfaceMesh m = contour(slab, opt, &st, &slab_keys, window.nearest ? &slab_nearest : nullptr);
    add_stats(total, st);
    ss.contour += seconds_since(t0);
    take(m, slab_keys, slab_nearest, k0, k0 + count - 1, k0 + count == window.hi + 1);
    ++ss.slabs;
  }
  free_storage(slab.bytes);
}

// --coarsen: every slab's coarse points finished as soon as the slab above
// them is read (coarsen/coarsen_slabs.hpp); averaged normals then come from
// the coarse mesh, as the in-memory contour makes them.
SurfaceMesh coarsen_streamed(PlaneSource& source, const ContourOptions& options, std::size_t memory_limit,
                             ContourStats& total, StreamStats& ss) {
  SlabCoarsening coarse(source.header().dims.data(), static_cast<Id>(options.isovalues.size()));
  double seconds = 0;
  const Id nz = source.header().dims[2];
  for_each_slab(source, options, memory_limit, PlaneWindow{0, nz - 1, true}, ss, total,
                [&](const SurfaceMesh& m, const std::vector<std::uint64_t>& keys,
                    const std::vector<std::uint64_t>& nearest, Id k0, Id k_last, bool last) {
                  const auto t0 = Clock::now();
                  coarse.add_slab(m, keys, nearest, k0, k_last, last);
                  seconds += seconds_since(t0);
                });
  const auto t0 = Clock::now();
  SurfaceMesh mesh = coarse.finish();
  if (options.normals == ContourNormals::Average) average_normals(mesh);
  total.coarsen = seconds + seconds_since(t0);
  total.triangles_before_coarsening = coarse.fine_triangles();
  ss.fine_points = coarse.fine_points();
  ss.most_fine_points_held = coarse.most_fine_points_held();
  return mesh;
}

}  // namespace

SurfaceMesh contour_streamed(PlaneSource& source, const ContourOptions& options, std::size_t memory_limit,
                             ContourStats* stats, StreamStats* stream_stats,
                             std::vector<std::uint64_t>* point_keys) {
  const retained_blocks::KeepNothing within_the_budget;
  const ImageGrid& head = source.header();
  check_streamable(head, options);
  StreamStats ss;
  ContourStats total;
  SurfaceMesh mesh;
  if (options.coarsen) {
    mesh = coarsen_streamed(source, options, memory_limit, total, ss);
  } else {
    const Id nx = head.dims[0], ny = head.dims[1], nz = head.dims[2];
    const bool average = options.normals == ContourNormals::Average;
    SlabPoints all{3ull * static_cast<std::uint64_t>(nx * ny * nz), average, {}, {}, {}, {}, {}, {}};
    all.corners.resize(options.isovalues.size());
    all.layers = LayerGrid{static_cast<std::uint64_t>(nx * ny), nz - 1, static_cast<Id>(options.isovalues.size())};
    for_each_slab(source, options, memory_limit, PlaneWindow{0, nz - 1, false}, ss, total,
                  [&](const SurfaceMesh& m, const std::vector<std::uint64_t>& keys,
                      const std::vector<std::uint64_t>& nearest, Id, Id, bool) {
                    all.append(m, keys, nearest);
                    ss.most_fine_points_held = static_cast<Id>(all.keys.size());
                  });
    const auto t0 = Clock::now();
    mesh = all.merge(point_keys, nullptr);
    ss.fine_points = mesh.num_points();
    ss.merge = seconds_since(t0);
  }
  if (stats) *stats = total;
  if (stream_stats) *stream_stats = ss;
  return mesh;
}

SurfaceMesh contour_planes_streamed(PlaneSource& source, const ContourOptions& options, std::size_t memory_limit,
                                    Id lo, Id hi, std::vector<std::uint64_t>& keys,
                                    std::vector<std::uint64_t>* nearest, StreamStats* stream_stats) {
  const retained_blocks::KeepNothing within_the_budget;
  const ImageGrid& head = source.header();
  check_streamable(head, options);
  if (options.coarsen || options.normals == ContourNormals::Average || lo < 0 || hi >= head.dims[2] || lo >= hi)
    throw std::logic_error("contour_planes_streamed: fine points only, without averaged normals, in the grid");
  const Id nxy = head.dims[0] * head.dims[1], nz = head.dims[2];
  StreamStats ss;
  ContourStats total;
  SlabPoints all{3ull * static_cast<std::uint64_t>(nxy * nz), false, {}, {}, {}, {}, {}, {}};
  all.corners.resize(options.isovalues.size());
  for_each_slab(source, options, memory_limit, PlaneWindow{lo, hi, nearest != nullptr}, ss, total,
                [&](const SurfaceMesh& m, const std::vector<std::uint64_t>& slab_keys,
                    const std::vector<std::uint64_t>& slab_nearest, Id, Id, bool) {
                  all.append(m, slab_keys, slab_nearest);
                  ss.most_fine_points_held = static_cast<Id>(all.keys.size());
                });
  const auto t0 = Clock::now();
  SurfaceMesh mesh = all.merge(&keys, nearest);
  ss.merge = seconds_since(t0);
  ss.fine_points = mesh.num_points();
  if (stream_stats) *stream_stats = ss;
  return mesh;
}

}  // namespace keymesh::generate
