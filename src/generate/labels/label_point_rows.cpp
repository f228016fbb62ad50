// Where the points of a streamed label surface lie (label_volume.hpp's
// point_rows): each point's padded row, read back from its key, and a key
// that ascends in the output's point order with the row never decreasing
// within a segment. A rank owns the points of its rows, and these keys let
// the distributed KEY-REDUCE split each segment by rank (labels_pieces).
//
// The keys (labels_surface_nets.cpp, labels_discrete_mc.cpp, label_volume.hpp):
//  - surface nets, network: the padded grid's cell (x fastest);
//  - surface nets, per label: 4 * cell + loop in the label's box (its voxels'
//    box grown by one), then 4 * cells + 2 * (3 * face cell + axis) + arc
//    for the face points: two runs per label (cells, then faces);
//  - discrete MC: 3 * padded point + axis (per label: within each part);
//  - coarse: the 2x2x2 block of cells (surface nets) or the padded point
//    (discrete MC), per label the label index + 1 above bit 44.
#include <algorithm>
#include <string>

#include "keymesh/core/error.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

constexpr int kLocalBits = 47;  // distributed::kSegmentShift (halo_piece.hpp), a layer above

struct Where {
  int segment = 0;
  std::uint64_t local = 0;
  Id row = 0;
};

// A fine surface nets point of part `s` (per label) or of the network (s < 0).
Where surface_nets_point(const LabelVolume& vol, int s, std::uint64_t key) {
  if (s < 0) {
    const auto cxy = static_cast<std::uint64_t>((vol.dims[0] - 1) * (vol.dims[1] - 1));
    return {0, key, static_cast<Id>(key / cxy)};
  }
  const auto& b = vol.box[static_cast<std::size_t>(s)];
  // The label's box grown by one point each way (labels_surface_nets.cpp's box_of).
  const auto cxy = static_cast<std::uint64_t>((b[3] - b[0] + 2) * (b[4] - b[1] + 2));
  const std::uint64_t cells = cxy * static_cast<std::uint64_t>(b[5] - b[2] + 2);
  const Id lo = b[2] - 1;
  if (key < 4 * cells) return {2 * s, key, lo + static_cast<Id>(key / 4 / cxy)};
  const std::uint64_t face_key = key - 4 * cells;
  return {2 * s + 1, face_key, lo + static_cast<Id>(face_key / 2 / 3 / cxy)};
}

Where coarse_point(const LabelVolume& vol, const LabelOptions& options, std::uint64_t key) {
  Where w;
  w.local = key & ((std::uint64_t{1} << 44) - 1);
  if (options.per_label) {
    const auto label = static_cast<LabelIndex>((key >> 44) - 1);
    w.segment = static_cast<int>(std::lower_bound(vol.selected.begin(), vol.selected.end(), label) -
                                 vol.selected.begin());
  }
  if (options.method == LabelMethod::SurfaceNets) {
    const auto bxy = static_cast<std::uint64_t>((vol.dims[0] / 2 + 1) * (vol.dims[1] / 2 + 1));
    w.row = 2 * static_cast<Id>(w.local / bxy);
  } else {
    w.row = static_cast<Id>(w.local / static_cast<std::uint64_t>(vol.nxy));
  }
  return w;
}

}  // namespace

int point_rows(const LabelVolume& vol, const LabelOptions& options, const std::vector<std::uint64_t>& keys,
               const std::vector<Id>& part_points, std::vector<std::uint64_t>& order_key, std::vector<Id>& row) {
  const std::size_t n = keys.size();
  order_key.resize(n);
  row.resize(n);
  const int parts = static_cast<int>(vol.selected.size());
  const bool surface_nets = options.method == LabelMethod::SurfaceNets;
  const int segments = !options.per_label ? 1 : options.coarsen || !surface_nets ? parts : 2 * parts;
  int part = 0;
  Id part_end = options.per_label && !part_points.empty() ? part_points[0] : static_cast<Id>(n);
  for (std::size_t p = 0; p < n; ++p) {
    while (options.per_label && !options.coarsen && static_cast<Id>(p) >= part_end && part + 1 < parts)
      part_end += part_points[static_cast<std::size_t>(++part)];
    Where w;
    if (options.coarsen) {
      w = coarse_point(vol, options, keys[p]);
    } else if (surface_nets) {
      w = surface_nets_point(vol, options.per_label ? part : -1, keys[p]);
    } else {
      w = {options.per_label ? part : 0, keys[p], static_cast<Id>(keys[p] / 3 / static_cast<std::uint64_t>(vol.nxy))};
    }
    if (w.local >> kLocalBits)
      throw LimitError("labels: point key " + std::to_string(w.local) + " exceeds 2^47 (the volume is too large "
                       "for pieces under mpirun)");
    order_key[p] = static_cast<std::uint64_t>(w.segment) << kLocalBits | w.local;
    row[p] = w.row;
    if (p > 0 && order_key[p] <= order_key[p - 1])
      throw LimitError("labels: points out of key order (internal error)");
  }
  return segments;
}

}  // namespace keymesh::generate::detail
