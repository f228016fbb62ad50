// Per-point history of a label surface (LabelOptions::history,
// docs/HISTORY.md): each point's element of the padded grid (the volume with
// one layer of background all round; padded point (i, j, k) is sample
// (i - 1, j - 1, k - 1), p = i + (nx + 2) * (j + (ny + 2) * k)), named
// alike by every path (in memory, slabs, ranks), since it is a function of
// the generator's own key and the label's box:
//  - discrete MC: the edge, 3 * p + axis (the generator's key), t = 0.5;
//  - surface nets: 16 * p + slot, p the cell's first corner, slot the
//    cell's loop (0..3; 0 in the network) or 4 + 2 * normal axis + arc for
//    a face point (per label), t = 0.5 (the cell's centre is p + t on every
//    axis).
#include <algorithm>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

// Surface nets: the generator's key of a point (a network cell of the whole
// padded grid; per label, 4 * cell + loop or a face key, in the label's
// box, labels_surface_nets.cpp) as 16 * padded point + slot.
std::uint64_t cell_history(const LabelVolume& vol, std::uint64_t key, const Id lo[3], const Id dims[3], bool per_label) {
  const Id cx = dims[0] - 1, cy = dims[1] - 1, cells = cx * cy * (dims[2] - 1);
  const Id k = static_cast<Id>(key);
  const bool face = per_label && k >= 4 * cells;
  const Id cell = !per_label ? k : face ? (k - 4 * cells) / 6 : k / 4;
  const Id slot = !per_label ? 0 : face ? 4 + (k - 4 * cells) % 6 : k % 4;
  const Id p = vol.at(lo[0] + cell % cx, lo[1] + (cell / cx) % cy, lo[2] + cell / (cx * cy));
  return 16 * static_cast<std::uint64_t>(p) + static_cast<std::uint64_t>(slot);
}

// Per point of a per-label surface, the index (in vol.selected) of its
// label: that of the faces using it (cell field `label`).
std::vector<std::size_t> point_labels(const LabelSurface& surface, const LabelVolume& vol) {
  const Field* label = surface.mesh.find_cell_field("label");
  const Id points = static_cast<Id>(surface.junction.size());
  std::vector<std::size_t> out(static_cast<std::size_t>(points), 0);
  if (!label) return out;
  const SurfaceMesh& m = surface.mesh;
  for (Id c = 0; c < m.num_cells(); ++c) {
    const auto value = static_cast<std::int64_t>(label->values[static_cast<std::size_t>(c)]);
    const auto s = std::lower_bound(vol.selected.begin(), vol.selected.end(), value,
                                    [&](LabelIndex l, std::int64_t v) { return vol.values[l] < v; }) -
                   vol.selected.begin();
    for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k) out[m.connectivity[k]] = static_cast<std::size_t>(s);
  }
  return out;
}

}  // namespace

void add_label_history(LabelSurface& surface, const LabelVolume& vol, const LabelOptions& options) {
  const Id points = static_cast<Id>(surface.junction.size());
  if (surface.keys.size() != static_cast<std::size_t>(points))
    throw InputError("labels: history: " + std::to_string(surface.keys.size()) + " point keys for " +
                     std::to_string(points) + " points (internal error)");
  surface.history_key.resize(static_cast<std::size_t>(points));
  if (options.method == LabelMethod::DiscreteMarchingCubes) {
    surface.history_key = surface.keys;  // already the padded grid's edges
  } else if (!options.per_label) {
    const Id lo[3] = {0, 0, 0}, dims[3] = {vol.dims[0], vol.dims[1], vol.dims[2]};
    parallel::for_each(points, [&](Id p) { surface.history_key[p] = cell_history(vol, surface.keys[p], lo, dims, false); });
  } else {
    const std::vector<std::size_t> label_of = point_labels(surface, vol);
    parallel::for_each(points, [&](Id p) {
      const std::size_t s = label_of[static_cast<std::size_t>(p)];
      Id lo[3], dims[3];  // the label's box (labels_surface_nets.cpp, box_of)
      for (int a = 0; a < 3; ++a) lo[a] = vol.box[s][a] - 1, dims[a] = vol.box[s][3 + a] - vol.box[s][a] + 3;
      surface.history_key[p] = cell_history(vol, surface.keys[p], lo, dims, true);
    });
  }
  surface.mesh.point_fields.push_back(Field{"history_t", 1, Array<float>(static_cast<std::size_t>(points), 0.5f)});
}

}  // namespace keymesh::generate::detail
