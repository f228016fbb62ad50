// contour_labels: scan the label map, run the chosen generator (its map step
// and KEY-REDUCE), smooth, and attach the label fields. See labels.hpp.
#include "keymesh/generate/labels/labels.hpp"

#include <chrono>
#include <cmath>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/core/progress.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "label_volume.hpp"

namespace keymesh::generate {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

void detail::check_label_options(const LabelOptions& options) {
  if (options.smooth_iterations < 0)
    throw InputError("labels: smoothing iterations " + std::to_string(options.smooth_iterations) + " is negative");
  if (!(options.relaxation > 0.0 && options.relaxation <= 1.0))
    throw InputError("labels: relaxation factor " + std::to_string(options.relaxation) + " is not in (0, 1]");
  if (options.history && options.coarsen)
    throw InputError("labels: history with coarsening: a coarsened point merges the points of several cells or "
                     "edges, so it has no one element to name");
}

void check_labels_input(const ImageGrid& grid, const LabelOptions& options) {
  detail::check_label_options(options);
  detail::check_label_grid(grid, options);
}

SurfaceMesh contour_labels(const ImageGrid& grid, const LabelOptions& options, LabelStats* stats,
                           std::vector<std::uint64_t>* history_key) {
  detail::check_label_options(options);
  LabelStats local;
  LabelStats& st = stats ? *stats : local;
  st = LabelStats{};
  auto t0 = Clock::now();
  progress::report("scan labels", 0.0);
  detail::LabelVolume vol = detail::scan_labels(grid, options);
  vol.coarse_keys = options.coarsen;
  vol.per_label = options.per_label;
  vol.keep_keys = options.history;
  progress::report(options.method == LabelMethod::SurfaceNets ? "surface nets" : "discrete marching cubes", 0.1);
  st.scan = seconds_since(t0);
  st.distinct_labels = vol.distinct_in_grid;
  st.surfaces = static_cast<Id>(vol.selected.size());

  detail::LabelSurface surface = options.method == LabelMethod::SurfaceNets
                                     ? detail::surface_nets(vol, options.per_label, st)
                                     : detail::discrete_marching_cubes(vol, options.per_label, st);
  SurfaceMesh mesh = detail::finish_label_mesh(surface, vol, options, st);
  if (history_key) *history_key = std::move(surface.history_key);
  return mesh;
}

SurfaceMesh detail::finish_label_mesh(LabelSurface& surface, const LabelVolume& vol, const LabelOptions& options,
                                      LabelStats& st) {
  if (options.history) detail::add_label_history(surface, vol, options);
  auto t0 = Clock::now();
  if (options.smooth_iterations > 0) progress::report("smooth", 0.6);
  st.guard_shortened +=
      detail::smooth_label_surface(surface, vol, options.method, options.smooth_iterations, options.relaxation);
  st.smooth = seconds_since(t0);
  if (options.coarsen) detail::coarsen_label_surface(surface, st);

  SurfaceMesh mesh = std::move(surface.mesh);
  // boundary_labels first, then `label` when the generator wrote one.
  Field pairs{"boundary_labels", 2, Array<float>(2 * surface.pair.size())};
  parallel::for_each(static_cast<Id>(surface.pair.size()), [&](Id t) {
    const std::uint32_t pq = surface.pair[static_cast<std::size_t>(t)];
    pairs.values[2 * t] = static_cast<float>(vol.values[pq >> 16]);
    pairs.values[2 * t + 1] = static_cast<float>(vol.values[pq & 0xffff]);
  });
  mesh.cell_fields.insert(mesh.cell_fields.begin(), std::move(pairs));
  return mesh;
}

std::vector<LabelPairCount> label_pair_counts(const SurfaceMesh& mesh) {
  std::vector<LabelPairCount> out;
  const Field* f = mesh.find_cell_field("boundary_labels");
  if (!f || f->components != 2) return out;
  const Id cells = mesh.num_cells();
  // Faces by pair: the pair's values as two 32-bit halves of a key (labels
  // are integers within +-2^24, offset to be non-negative).
  auto half = [](float v) { return static_cast<std::uint64_t>(static_cast<std::int64_t>(v) + kMaxLabelMagnitude); };
  std::vector<std::uint64_t> face_key(static_cast<std::size_t>(cells));
  parallel::for_each(cells, [&](Id c) { face_key[c] = half(f->values[2 * c]) << 32 | half(f->values[2 * c + 1]); });
  const auto faces = keyreduce::partition_sort(face_key.data(), cells, 58, keyreduce::Order::Build);
  // Points by (pair, point): distinct keys per pair.
  std::vector<std::uint64_t> corner_key;
  corner_key.reserve(mesh.connectivity.size());
  for (Id c = 0; c < cells; ++c)
    for (std::uint64_t k = mesh.cell_begin(c); k < mesh.cell_end(c); ++k)
      corner_key.push_back(static_cast<std::uint64_t>(faces.index_map[c]) << 32 | mesh.connectivity[k]);
  const auto corners = keyreduce::partition_sort(corner_key.data(), static_cast<Id>(corner_key.size()),
                                                 32 + parallel::bits_needed<std::uint64_t>(
                                                          static_cast<std::uint64_t>(faces.num_groups())),
                                                 keyreduce::Order::Skip);
  out.resize(static_cast<std::size_t>(faces.num_groups()));
  for (Id g = 0; g < faces.num_groups(); ++g) {
    const std::uint64_t k = faces.unique_keys[g];
    out[g].first = static_cast<std::int64_t>(k >> 32) - kMaxLabelMagnitude;
    out[g].second = static_cast<std::int64_t>(k & 0xffffffffu) - kMaxLabelMagnitude;
    out[g].faces = faces.count(g);
  }
  for (std::uint64_t k : corners.unique_keys) ++out[k >> 32].points;
  return out;
}

}  // namespace keymesh::generate
