#include "label_volume.hpp"

#include <algorithm>
#include <limits>
#include <string>
#include <type_traits>

#include "keymesh/core/error.hpp"
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
    std::vector<std::vector<std::int64_t>> runs(static_cast<std::size_t>(chunks));
    parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
      auto& r = runs[static_cast<std::size_t>(c)];
      for (Id i = b; i < e; ++i)
        if (i == b || samples[i] != samples[i - 1]) r.push_back(samples[i]);
      std::sort(r.begin(), r.end());
      r.erase(std::unique(r.begin(), r.end()), r.end());
    });
    for (const auto& r : runs) out.insert(out.end(), r.begin(), r.end());
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }
  return out;
}

Id index_of(const std::vector<std::int64_t>& values, std::int64_t v) {
  return static_cast<Id>(std::lower_bound(values.begin(), values.end(), v) - values.begin());
}

template <class T>
LabelVolume scan_typed(const ImageGrid& grid, const T* samples, const LabelOptions& opt) {
  LabelVolume vol;
  const Id nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  vol.dims = {nx + 2, ny + 2, nz + 2};
  vol.nxy = vol.dims[0] * vol.dims[1];
  vol.n = vol.nxy * vol.dims[2];
  vol.origin = grid.origin;
  vol.spacing = grid.spacing;

  vol.values = distinct_values(samples, grid.num_points());
  vol.distinct_in_grid = static_cast<Id>(vol.values.size());
  for (std::int64_t v : {vol.values.front(), vol.values.back()})
    if (v > kMaxLabelMagnitude || v < -kMaxLabelMagnitude)
      throw InputError("labels: label " + std::to_string(v) + " is past the supported magnitude 2^24 (16777216): " +
                       "boundary_labels is a float32 field");
  // The background joins the values (it pads the grid) if absent.
  if (!std::binary_search(vol.values.begin(), vol.values.end(), opt.background))
    vol.values.insert(vol.values.begin() + index_of(vol.values, opt.background), opt.background);
  if (static_cast<Id>(vol.values.size()) > kMaxDistinctLabels)
    throw InputError("labels: the volume holds " + std::to_string(vol.values.size()) +
                     " distinct labels (background included), more than the supported " +
                     std::to_string(kMaxDistinctLabels));
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
  for (std::size_t l = 0; l < keep.size(); ++l)
    if (keep[l]) vol.selected.push_back(static_cast<LabelIndex>(l));

  // Label value -> index, as the padded grid stores it (background when not
  // selected). Small types use a table over their range; int32 a binary
  // search once per run of equal samples.
  auto map_of = [&](std::int64_t v) {
    const Id at = index_of(vol.values, v);
    return keep[static_cast<std::size_t>(at)] ? static_cast<LabelIndex>(at) : vol.background;
  };
  std::vector<LabelIndex> table;
  constexpr bool small = sizeof(T) <= 2;
  constexpr Id lowest = static_cast<Id>(std::numeric_limits<T>::lowest());
  if constexpr (small) {
    table.assign(std::size_t{1} << (8 * sizeof(T)), vol.background);
    for (std::int64_t v : vol.values)
      if (v >= lowest && v <= static_cast<Id>(std::numeric_limits<T>::max()))
        table[static_cast<std::size_t>(v - lowest)] = map_of(v);
  }

  vol.index.assign(static_cast<std::size_t>(vol.n), vol.background);
  const Id nl = static_cast<Id>(vol.values.size());
  // Voxel counts and boxes per label index, per chunk of z-planes, merged
  // in chunk order (sums and min/max: any order gives the same result).
  const int chunks = parallel::chunk_count(nz, 8);
  std::vector<std::vector<Id>> counts(static_cast<std::size_t>(chunks));
  std::vector<std::vector<std::array<Id, 6>>> boxes(static_cast<std::size_t>(chunks));
  parallel::for_each_chunk(nz, chunks, [&](Id kb, Id ke, int c) {
    auto& cnt = counts[static_cast<std::size_t>(c)];
    auto& box = boxes[static_cast<std::size_t>(c)];
    cnt.assign(static_cast<std::size_t>(nl), 0);
    const Id big = std::numeric_limits<Id>::max();
    box.assign(static_cast<std::size_t>(nl), {big, big, big, -1, -1, -1});
    for (Id k = kb; k < ke; ++k)
      for (Id j = 0; j < ny; ++j) {
        const T* in = samples + j * nx + k * nx * ny;
        LabelIndex* out = vol.index.data() + vol.at(1, j + 1, k + 1);
        LabelIndex last = vol.background;
        for (Id i = 0; i < nx; ++i) {
          LabelIndex l;
          if constexpr (small) {
            l = table[static_cast<std::size_t>(static_cast<Id>(in[i]) - lowest)];
          } else {
            l = (i > 0 && in[i] == in[i - 1]) ? last : map_of(in[i]);
          }
          last = l;
          out[i] = l;
          if (l == vol.background) continue;
          ++cnt[l];
          auto& b = box[l];
          const Id p[3] = {i + 1, j + 1, k + 1};
          for (int a = 0; a < 3; ++a) {
            b[a] = std::min(b[a], p[a]);
            b[3 + a] = std::max(b[3 + a], p[a]);
          }
        }
      }
  });
  for (LabelIndex l : vol.selected) {
    Id count = 0;
    std::array<Id, 6> b = boxes[0][l];
    for (int c = 0; c < chunks; ++c) {
      count += counts[static_cast<std::size_t>(c)][l];
      for (int a = 0; a < 3; ++a) {
        b[a] = std::min(b[a], boxes[static_cast<std::size_t>(c)][l][a]);
        b[3 + a] = std::max(b[3 + a], boxes[static_cast<std::size_t>(c)][l][3 + a]);
      }
    }
    vol.voxels.push_back(count);
    vol.box.push_back(b);
  }
  return vol;
}

}  // namespace

LabelVolume scan_labels(const ImageGrid& grid, const LabelOptions& options) {
  for (int a = 0; a < 3; ++a)
    if (grid.dims[a] < 1)
      throw InputError("labels: grid has " + std::to_string(grid.dims[a]) + " points along axis " + "xyz"[a]);
  if (static_cast<Id>(grid.byte_count()) != grid.num_points() * static_cast<Id>(scalar_size(grid.type)))
    throw InputError("labels: grid holds " + std::to_string(grid.byte_count()) + " bytes, dims need " +
                     std::to_string(grid.num_points() * static_cast<Id>(scalar_size(grid.type))));
  if (grid.type == ScalarType::Float32 || grid.type == ScalarType::Float64)
    throw InputError(std::string("labels: a ") + scalar_type_name(grid.type) +
                     " volume is not a label map (integer samples: uint8, int8, uint16, int16, int32)");
  if (options.background > kMaxLabelMagnitude || options.background < -kMaxLabelMagnitude)
    throw InputError("labels: background " + std::to_string(options.background) +
                     " is past the supported magnitude 2^24");
  return visit_scalars(grid, [&](const auto* samples) -> LabelVolume {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(samples)>>;
    if constexpr (std::is_floating_point_v<T>) {
      throw InputError("labels: float volume");
    } else {
      return scan_typed<T>(grid, samples, options);
    }
  });
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
