#include "label_volume.hpp"

#include <algorithm>
#include <iterator>
#include <limits>
#include <string>
#include <type_traits>

#include "keymesh/core/error.hpp"
#include "keymesh/mesh/label_scalars.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::generate::detail {

namespace {

// The sorted distinct values of the samples. Label maps hold long runs of
// one value, so each chunk keeps one value per run before sorting.
template <class T>
std::vector<std::int64_t> distinct_values(const T* samples, Id n) {
  std::vector<std::int64_t> out;
  if constexpr (sizeof(T) <= 2) {
    // A presence table over the type's whole range.
    constexpr Id range = Id{1} << (8 * sizeof(T));
    constexpr Id lowest = static_cast<Id>(std::numeric_limits<T>::lowest());
    const int chunks = parallel::chunk_count(n, 1 << 16);
    std::vector<std::vector<std::uint8_t>> seen(static_cast<std::size_t>(chunks));
    parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
      auto& s = seen[static_cast<std::size_t>(c)];
      s.assign(static_cast<std::size_t>(range), 0);
      for (Id i = b; i < e; ++i) s[static_cast<std::size_t>(static_cast<Id>(samples[i]) - lowest)] = 1;
    });
    for (Id v = 0; v < range; ++v) {
      bool any = false;
      for (const auto& s : seen) any = any || s[static_cast<std::size_t>(v)];
      if (any) out.push_back(v + lowest);
    }
  } else {
    const int chunks = parallel::chunk_count(n, 1 << 16);
    std::vector<std::vector<T>> runs(static_cast<std::size_t>(chunks));
    parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
      auto& r = runs[static_cast<std::size_t>(c)];
      for (Id i = b; i < e; ++i)
        if (i == b || samples[i] != samples[i - 1]) r.push_back(samples[i]);
      std::sort(r.begin(), r.end());
      r.erase(std::unique(r.begin(), r.end()), r.end());
    });
    std::vector<T> all;
    for (const auto& r : runs) all.insert(all.end(), r.begin(), r.end());
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    // Labels are held as int64: a uint64 id past 2^63 - 1 is refused by
    // name (docs/decisions/wide-label-types.md).
    if constexpr (std::is_same_v<T, std::uint64_t>)
      if (!all.empty() && all.back() > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
        throw InputError("labels: label " + std::to_string(all.back()) +
                         " is past 2^63 - 1 (9223372036854775807), the largest label keymesh holds");
    out.assign(all.begin(), all.end());
  }
  return out;
}

Id index_of(const std::vector<std::int64_t>& values, std::int64_t v) {
  return static_cast<Id>(std::lower_bound(values.begin(), values.end(), v) - values.begin());
}

// The value -> stored index table of a small type (over its whole range).
template <class T>
std::vector<LabelIndex> small_table(const LabelVolume& vol) {
  constexpr Id lowest = static_cast<Id>(std::numeric_limits<T>::lowest());
  std::vector<LabelIndex> table(std::size_t{1} << (8 * sizeof(T)), vol.background);
  for (std::size_t at = 0; at < vol.values.size(); ++at) {
    const std::int64_t v = vol.values[at];
    if (v >= lowest && v <= static_cast<Id>(std::numeric_limits<T>::max()))
      table[static_cast<std::size_t>(v - lowest)] = vol.stored[at];
  }
  return table;
}

// Maps the planes' samples into the window, counting voxels and boxes per
// label index per chunk of z-planes, merged in chunk order (sums and
// min/max: any order gives the same result).
template <class T>
void map_typed(LabelVolume& vol, const T* samples, const std::array<Id, 3>& dims, Id first, LabelCounts* counts) {
  const Id nx = dims[0], ny = dims[1], nz = dims[2];
  constexpr bool small = sizeof(T) <= 2;
  constexpr Id lowest = static_cast<Id>(std::numeric_limits<T>::lowest());
  std::vector<LabelIndex> table;
  if constexpr (small) table = small_table<T>(vol);
  // Wider types: a binary search once per run of equal samples.
  auto map_of = [&](T v) {
    return vol.stored[static_cast<std::size_t>(index_of(vol.values, static_cast<std::int64_t>(v)))];
  };
  const Id nl = static_cast<Id>(vol.values.size());
  const int chunks = parallel::chunk_count(nz, 8);
  std::vector<LabelCounts> part(static_cast<std::size_t>(chunks));
  parallel::for_each_chunk(nz, chunks, [&](Id kb, Id ke, int c) {
    LabelCounts& cnt = part[static_cast<std::size_t>(c)];
    cnt.reset(nl);
    for (Id k = kb; k < ke; ++k)
      for (Id j = 0; j < ny; ++j) {
        const T* in = samples + j * nx + k * nx * ny;
        LabelIndex* out = vol.index.data() + (vol.at(1, j + 1, first + k + 1) - vol.first_plane * vol.nxy);
        LabelIndex last = vol.background;
        for (Id i = 0; i < nx; ++i) {
          LabelIndex l;
          if constexpr (small) {
            l = table[static_cast<std::size_t>(static_cast<Id>(in[i]) - lowest)];
          } else {  // int32 and the wide label types
            l = (i > 0 && in[i] == in[i - 1]) ? last : map_of(in[i]);
          }
          last = l;
          out[i] = l;
          if (l == vol.background) continue;
          ++cnt.voxels[l];
          auto& b = cnt.box[l];
          const Id p[3] = {i + 1, j + 1, first + k + 1};
          for (int a = 0; a < 3; ++a) {
            b[a] = std::min(b[a], p[a]);
            b[3 + a] = std::max(b[3 + a], p[a]);
          }
        }
      }
  });
  if (!counts) return;
  if (counts->voxels.empty()) counts->reset(nl);
  for (const LabelCounts& c : part) counts->merge(c);
}

}  // namespace

void LabelCounts::reset(Id labels) {
  const Id big = std::numeric_limits<Id>::max();
  voxels.assign(static_cast<std::size_t>(labels), 0);
  box.assign(static_cast<std::size_t>(labels), {big, big, big, -1, -1, -1});
}

void LabelCounts::merge(const LabelCounts& other) {
  for (std::size_t l = 0; l < voxels.size(); ++l) {
    voxels[l] += other.voxels[l];
    for (int a = 0; a < 3; ++a) {
      box[l][a] = std::min(box[l][a], other.box[l][a]);
      box[l][3 + a] = std::max(box[l][3 + a], other.box[l][3 + a]);
    }
  }
}

void check_label_grid(const ImageGrid& header, const LabelOptions& options, LabelRange range) {
  for (int a = 0; a < 3; ++a)
    if (header.dims[a] < 1)
      throw InputError("labels: grid has " + std::to_string(header.dims[a]) + " points along axis " + "xyz"[a]);
  if (header.type == ScalarType::Float32 || header.type == ScalarType::Float64)
    throw InputError(std::string("labels: a ") + scalar_type_name(header.type) +
                     " volume is not a label map (integer samples: uint8, int8, uint16, int16, int32, uint32, int64, uint64)");
  if (range == LabelRange::Float32Fields &&
      (options.background > kMaxLabelMagnitude || options.background < -kMaxLabelMagnitude))
    throw InputError("labels: background " + std::to_string(options.background) +
                     " is past the supported magnitude 2^24");
}

std::vector<std::int64_t> distinct_labels(const ImageGrid& samples) {
  return visit_any_scalars(samples, [&](const auto* s) -> std::vector<std::int64_t> {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(s)>>;
    if constexpr (std::is_floating_point_v<T>) {
      throw InputError("labels: float volume");
    } else {
      return distinct_values(s, samples.num_points());
    }
  });
}

void merge_distinct(std::vector<std::int64_t>& into, const std::vector<std::int64_t>& more) {
  std::vector<std::int64_t> out;
  out.reserve(into.size() + more.size());
  std::set_union(into.begin(), into.end(), more.begin(), more.end(), std::back_inserter(out));
  into.swap(out);
  // Past the limit already: stop growing (an int32 noise volume).
  if (static_cast<Id>(into.size()) > kMaxDistinctLabels + 1) into.resize(static_cast<std::size_t>(kMaxDistinctLabels + 1));
}

LabelVolume label_table(const ImageGrid& header, std::vector<std::int64_t> values, const LabelOptions& opt,
                        LabelRange range) {
  LabelVolume vol;
  const Id nx = header.dims[0], ny = header.dims[1], nz = header.dims[2];
  vol.dims = {nx + 2, ny + 2, nz + 2};
  vol.nxy = vol.dims[0] * vol.dims[1];
  vol.n = vol.nxy * vol.dims[2];
  vol.origin = header.origin;
  vol.spacing = header.spacing;
  vol.values = std::move(values);
  vol.distinct_in_grid = static_cast<Id>(vol.values.size());
  for (std::int64_t v : {vol.values.front(), vol.values.back()})
    if (range == LabelRange::Float32Fields && (v > kMaxLabelMagnitude || v < -kMaxLabelMagnitude))
      throw InputError("labels: label " + std::to_string(v) + " is past 2^24 (16777216), which the float32 cell " +
                       "field boundary_labels cannot hold exactly; --format precomputed keeps 64-bit ids exact");
  // The background joins the values (it pads the grid) if absent.
  if (!std::binary_search(vol.values.begin(), vol.values.end(), opt.background))
    vol.values.insert(vol.values.begin() + index_of(vol.values, opt.background), opt.background);
  if (static_cast<Id>(vol.values.size()) > kMaxDistinctLabels) {
    // A list merge_distinct capped (kMaxDistinctLabels + 1 values) says only
    // that there are at least that many; any other list is the true count.
    const bool capped = vol.distinct_in_grid == kMaxDistinctLabels + 1;
    throw InputError("labels: the volume holds " +
                     (capped ? "at least " + std::to_string(kMaxDistinctLabels + 1) : std::to_string(vol.values.size())) +
                     " distinct labels (background included), more than the supported " +
                     std::to_string(kMaxDistinctLabels));
  }
  vol.background = static_cast<LabelIndex>(index_of(vol.values, opt.background));

  // Selection: a label not selected becomes background.
  std::vector<std::uint8_t> keep(vol.values.size(), opt.labels.empty() ? 1 : 0);
  for (std::int64_t v : opt.labels) {
    if (v == opt.background)
      throw InputError("labels: label " + std::to_string(v) + " is the background (--background)");
    const Id at = index_of(vol.values, v);
    if (at == static_cast<Id>(vol.values.size()) || vol.values[static_cast<std::size_t>(at)] != v)
      throw InputError("labels: the volume holds no voxel of label " + std::to_string(v));
    keep[static_cast<std::size_t>(at)] = 1;
  }
  keep[vol.background] = 0;
  vol.stored.resize(vol.values.size());
  for (std::size_t l = 0; l < keep.size(); ++l) {
    vol.stored[l] = keep[l] ? static_cast<LabelIndex>(l) : vol.background;
    if (keep[l]) vol.selected.push_back(static_cast<LabelIndex>(l));
  }
  return vol;
}

void allocate_window(LabelVolume& vol, Id first_plane, Id planes) {
  vol.first_plane = first_plane;
  vol.index.assign(static_cast<std::size_t>(planes * vol.nxy), vol.background);
}

void map_planes(LabelVolume& vol, const ImageGrid& planes, Id first, LabelCounts* counts) {
  visit_any_scalars(planes, [&](const auto* samples) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(samples)>>;
    if constexpr (std::is_floating_point_v<T>) {
      throw InputError("labels: float volume");
    } else {
      map_typed<T>(vol, samples, planes.dims, first, counts);
    }
  });
}

void set_boxes(LabelVolume& vol, const LabelCounts& counts) {
  vol.voxels.clear();
  vol.box.clear();
  for (LabelIndex l : vol.selected) {
    vol.voxels.push_back(counts.voxels[l]);
    vol.box.push_back(counts.box[l]);
  }
}

LabelVolume scan_labels(const ImageGrid& grid, const LabelOptions& options, LabelRange range) {
  check_label_grid(grid, options, range);
  if (static_cast<Id>(grid.byte_count()) != grid.num_points() * static_cast<Id>(scalar_size(grid.type)))
    throw InputError("labels: grid holds " + std::to_string(grid.byte_count()) + " bytes, dims need " +
                     std::to_string(grid.num_points() * static_cast<Id>(scalar_size(grid.type))));
  LabelVolume vol = label_table(grid, distinct_labels(grid), options, range);
  allocate_window(vol, 0, vol.dims[2]);
  LabelCounts counts;
  map_planes(vol, grid, 0, &counts);
  set_boxes(vol, counts);
  return vol;
}

void append_surfaces(std::vector<LabelSurface>& parts, LabelSurface& out) {
  for (LabelSurface& part : parts) {
    const auto base = static_cast<PointIndex>(out.junction.size());
    for (PointIndex c : part.mesh.connectivity) out.mesh.connectivity.push_back(base + c);
    auto append = [](auto& to, const auto& from) { to.insert(to.end(), from.begin(), from.end()); };
    append(out.mesh.points, part.mesh.points);
    append(out.pair, part.pair);
    append(out.junction, part.junction);
    append(out.border_axes, part.border_axes);
    append(out.cell_centre, part.cell_centre);
    append(out.keys, part.keys);
    append(out.coarse, part.coarse);
    append(out.ghost_face, part.ghost_face);
    for (const Field& f : part.mesh.cell_fields) {
      Field* to = nullptr;
      for (Field& g : out.mesh.cell_fields) to = g.name == f.name ? &g : to;
      if (!to) to = &out.mesh.cell_fields.emplace_back(Field{f.name, f.components, {}});
      append(to->values, f.values);
    }
    part = LabelSurface{};
  }
}

}  // namespace keymesh::generate::detail
