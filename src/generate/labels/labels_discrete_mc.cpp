// Discrete marching cubes on a label map (see keymesh/generate/labels/labels.hpp):
// each selected label's indicator, cut out on the label's box (its voxels'
// bounding box grown by one point, background all round), is contoured at
// 0.5 by keymesh's marching cubes, which welds it by edge keys. The label
// surfaces' keys are then made global edge keys of the padded grid, and one
// more KEY-REDUCE (dense plan) over them shares the point of an edge
// between the two labels at its ends.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/core/free_storage.hpp"
#include "keymesh/core/progress.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// One label's surface: triangles over global edge keys of the padded grid.
struct LabelTriangles {
  std::vector<std::uint64_t> corner_keys;  // 3 per triangle
};

// Only the cubes of rows [rows.first, rows.second) of the padded grid (a
// slab of a streamed volume; a cube's row is its lower plane).
LabelTriangles contour_one_label(const LabelVolume& vol, std::size_t s, std::pair<Id, Id> rows) {
  const LabelIndex label = vol.selected[s];
  std::array<Id, 3> lo{}, dims{};
  for (int a = 0; a < 3; ++a) {
    lo[a] = vol.box[s][a] - 1;
    dims[a] = vol.box[s][3 + a] - vol.box[s][a] + 3;
  }
  const Id first_row = std::max(rows.first, lo[2]), end_row = std::min(rows.second, lo[2] + dims[2] - 1);
  if (end_row <= first_row) return {};
  dims[2] = end_row - first_row + 1;
  lo[2] = first_row;
  ImageGrid indicator;
  indicator.allocate(dims, ScalarType::UInt8);
  auto* ind = reinterpret_cast<std::uint8_t*>(indicator.data());
  for (Id k = 0; k < dims[2]; ++k)
    for (Id j = 0; j < dims[1]; ++j) {
      const LabelIndex* in = vol.row(vol.at(lo[0], lo[1] + j, lo[2] + k));
      std::uint8_t* out = ind + (k * dims[1] + j) * dims[0];
      for (Id i = 0; i < dims[0]; ++i) out[i] = in[i] == label;
    }
  // The labels' contours run on worker threads; only contour_labels reports
  // progress (on the calling thread), not each label's marching cubes.
  const progress::ScopedHook silent{progress::Hook{}};
  ContourOptions opt;
  opt.isovalues = {0.5};
  opt.scalars = false;
  std::vector<std::uint64_t> local_keys;
  const SurfaceMesh mesh = contour(indicator, opt, nullptr, &local_keys);
  // Local edge 3 * (i + j dx + k dx dy) + axis -> the same edge of the padded grid.
  LabelTriangles out;
  out.corner_keys.resize(mesh.connectivity.size());
  const Id dxy = dims[0] * dims[1];
  for (std::size_t c = 0; c < mesh.connectivity.size(); ++c) {
    const std::uint64_t key = local_keys[mesh.connectivity[c]];
    const Id point = static_cast<Id>(key / 3), axis = static_cast<Id>(key % 3);
    const Id i = point % dims[0], j = (point / dims[0]) % dims[1], k = point / dxy;
    out.corner_keys[c] = static_cast<std::uint64_t>(3 * vol.at(lo[0] + i, lo[1] + j, lo[2] + k) + axis);
  }
  return out;
}

// Welds triangles given by global edge keys (dense plan over the padded
// grid's 3N edges) and appends them with their points to `out`; `label`
// (an index) is the region whose surface they are.
void weld_and_append(const LabelVolume& vol, const std::vector<std::uint64_t>& corner_keys,
                     const std::vector<LabelIndex>& triangle_label, LabelSurface& out) {
  const Id corners = static_cast<Id>(corner_keys.size());
  // A window of a streamed volume sorts (its keys span the whole grid).
  auto groups = vol.window ? keyreduce::partition_sort(corner_keys.data(), corners,
                                                       parallel::bits_needed<std::uint64_t>(3 * vol.n),
                                                       keyreduce::Order::Skip)
                           : keyreduce::partition_dense(corner_keys.data(), corners,
                                                        static_cast<std::uint64_t>(3 * vol.n), keyreduce::Order::Skip);
  const Id points = groups.num_groups();
  const std::uint32_t base = static_cast<std::uint32_t>(out.junction.size());
  const std::size_t c0 = out.mesh.connectivity.size();
  out.mesh.connectivity.resize(c0 + static_cast<std::size_t>(corners));
  parallel::for_each(corners, [&](Id c) { out.mesh.connectivity[c0 + static_cast<std::size_t>(c)] = base + groups.index_map[c]; });
  // Every triangle's pair: its label and the label across its first corner's edge.
  const Id triangles = corners / 3;
  const std::size_t t0 = out.pair.size();
  out.pair.resize(t0 + static_cast<std::size_t>(triangles));
  parallel::for_each(triangles, [&](Id t) {
    const std::uint64_t key = corner_keys[static_cast<std::size_t>(3 * t)];
    const Id p = static_cast<Id>(key / 3);
    const Id q = p + (key % 3 == 0 ? 1 : key % 3 == 1 ? vol.dims[0] : vol.nxy);
    const LabelIndex l = triangle_label[static_cast<std::size_t>(t)];
    const LabelIndex m = vol.label(p) == l ? vol.label(q) : vol.label(p);
    out.pair[t0 + static_cast<std::size_t>(t)] = l < m ? (std::uint32_t{l} << 16 | m) : (std::uint32_t{m} << 16 | l);
  });
  // Points at edge midpoints; a junction when the cells around the edge
  // hold three labels or more; on the padded border along the edge's axis
  // when one end is a padding point.
  const std::size_t p0 = out.junction.size();
  out.junction.resize(p0 + static_cast<std::size_t>(points));
  out.border_axes.resize(p0 + static_cast<std::size_t>(points));
  out.mesh.points.resize(3 * (p0 + static_cast<std::size_t>(points)));
  if (vol.coarse_keys) out.coarse.resize(p0 + static_cast<std::size_t>(points));
  const LabelIndex part_label = triangle_label.empty() ? LabelIndex{0} : triangle_label[0];  // per label: the one
  const Id stride[3] = {1, vol.dims[0], vol.nxy};
  parallel::for_each(points, [&](Id g) {
    const std::uint64_t key = groups.unique_keys[static_cast<std::size_t>(g)];
    const Id p = static_cast<Id>(key / 3);
    const int axis = static_cast<int>(key % 3);
    const Id ijk[3] = {p % vol.dims[0], (p / vol.dims[0]) % vol.dims[1], p / vol.nxy};
    const std::size_t at = p0 + static_cast<std::size_t>(g);
    for (int a = 0; a < 3; ++a)
      out.mesh.points[3 * at + a] = static_cast<float>(vol.coord(a, static_cast<double>(ijk[a]) + (a == axis ? 0.5 : 0.0)));
    out.border_axes[at] = static_cast<std::uint8_t>((ijk[axis] == 0 || ijk[axis] + 1 == vol.dims[axis]) ? 1u << axis : 0u);
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    LabelIndex seen[3];
    int n = 0;
    for (int end = 0; end < 2 && n < 3; ++end)
      for (int du = -1; du <= 1; ++du)
        for (int dv = -1; dv <= 1; ++dv) {
          const Id cu = ijk[u] + du, cv = ijk[v] + dv;
          if (cu < 0 || cv < 0 || cu >= vol.dims[u] || cv >= vol.dims[v]) continue;
          const LabelIndex l = vol.label(p + end * stride[axis] + du * stride[u] + dv * stride[v]);
          bool dup = false;
          for (int i = 0; i < n; ++i) dup = dup || seen[i] == l;
          if (!dup && n < 3) seen[n++] = l;
        }
    out.junction[at] = n >= 3;
    if (vol.coarse_keys) out.coarse[at] = vol.part_key(static_cast<std::uint64_t>(p), part_label);
  }, 1024);
  if (vol.window || vol.keep_keys) out.keys.insert(out.keys.end(), groups.unique_keys.begin(), groups.unique_keys.end());
}

}  // namespace

LabelSurface discrete_marching_cubes(const LabelVolume& vol, bool per_label_surfaces, LabelStats& st) {
  const std::size_t n = vol.selected.size();
  std::vector<LabelTriangles> surfaces(n);
  auto t0 = Clock::now();
  parallel::for_each_dynamic(static_cast<Id>(n),
                             [&](Id s) { surfaces[static_cast<std::size_t>(s)] = contour_one_label(vol, static_cast<std::size_t>(s), {0, vol.dims[2]}); }, 1);
  st.generate += seconds_since(t0);
  t0 = Clock::now();
  LabelSurface out;
  Array<float> label_field;
  for (const auto& s : surfaces) st.soup_corners += static_cast<Id>(s.corner_keys.size());
  if (per_label_surfaces) {
    // Each label's surface with its own points, in label order.
    std::vector<LabelSurface> parts(n);
    parallel::for_each_dynamic(static_cast<Id>(n), [&](Id s) {
      const auto& keys = surfaces[static_cast<std::size_t>(s)].corner_keys;
      weld_and_append(vol, keys, std::vector<LabelIndex>(keys.size() / 3, vol.selected[static_cast<std::size_t>(s)]),
                      parts[static_cast<std::size_t>(s)]);
    }, 1);
    append_surfaces(parts, out);
  } else {
    // One mesh: the labels' triangles in label order, points shared.
    std::vector<std::uint64_t> keys;
    std::vector<LabelIndex> triangle_label;
    keys.reserve(static_cast<std::size_t>(st.soup_corners));
    for (std::size_t s = 0; s < n; ++s) {
      keys.insert(keys.end(), surfaces[s].corner_keys.begin(), surfaces[s].corner_keys.end());
      triangle_label.insert(triangle_label.end(), surfaces[s].corner_keys.size() / 3, vol.selected[s]);
      free_storage(surfaces[s].corner_keys);
    }
    weld_and_append(vol, keys, triangle_label, out);
    for (LabelIndex l : triangle_label) label_field.push_back(static_cast<float>(vol.values[l]));
  }
  if (per_label_surfaces) {
    for (std::size_t s = 0; s < n; ++s)
      label_field.insert(label_field.end(), surfaces[s].corner_keys.size() / 3, static_cast<float>(vol.values[vol.selected[s]]));
  }
  out.mesh.cell_fields.push_back(Field{"label", 1, std::move(label_field)});
  st.weld += seconds_since(t0);
  return out;
}

std::vector<LabelSurface> discrete_marching_cubes_rows(const LabelVolume& vol, std::pair<Id, Id> rows,
                                                       LabelStats& st) {
  const std::size_t n = vol.selected.size();
  std::vector<LabelSurface> parts(n);
  parallel::for_each_dynamic(static_cast<Id>(n), [&](Id s) {
    const std::size_t at = static_cast<std::size_t>(s);
    const LabelTriangles tri = contour_one_label(vol, at, rows);
    const std::size_t triangles = tri.corner_keys.size() / 3;
    weld_and_append(vol, tri.corner_keys, std::vector<LabelIndex>(triangles, vol.selected[at]), parts[at]);
    parts[at].mesh.cell_fields.push_back(
        Field{"label", 1, Array<float>(triangles, static_cast<float>(vol.values[vol.selected[at]]))});
  }, 1);
  for (const LabelSurface& p : parts) st.soup_corners += static_cast<Id>(p.mesh.connectivity.size());
  return parts;
}

}  // namespace keymesh::generate::detail
