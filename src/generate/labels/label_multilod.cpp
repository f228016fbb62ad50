// Multilod label surfaces (see keymesh/generate/labels/labels_multilod.hpp):
// every segment's surface made once on the volume (or on a chunk task's
// box and halo), smoothed, keyed globally, then cut into chunks and
// coarsened per chunk (label_chunk_clip.cpp, label_chunk_lods.cpp).
#include "keymesh/generate/labels/labels_multilod.hpp"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <exception>
#include <optional>
#include <string>
#include <tuple>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/task_pipeline.hpp"
#include "label_chunks.hpp"
#include "label_volume.hpp"

namespace keymesh::generate {

namespace {

using detail::LabelSurface;
using detail::LabelVolume;
using detail::SegmentSurface;

constexpr int kCellBits = 18;

void check_multilod_options(const MultilodOptions& o) {
  detail::check_label_options(o.labels);
  if (o.labels.coarsen)
    throw InputError("labels: coarsening does not apply to a multilod output (its levels of detail coarsen)");
  if (o.vertex_quantization_bits != 10 && o.vertex_quantization_bits != 16)
    throw InputError("labels: vertex quantization of " + std::to_string(o.vertex_quantization_bits) +
                     " bits (Neuroglancer's are 10 and 16)");
  if (o.lods < 1 || o.lods > 20) throw InputError("labels: " + std::to_string(o.lods) + " levels of detail (1 to 20)");
  for (int a = 0; a < 3; ++a)
    if (o.chunk_shape[a] < 2)
      throw InputError("labels: chunk shape " + std::to_string(o.chunk_shape[a]) + " along " + "xyz"[a] +
                       " is below 2 samples");
}

// Padded grid coordinates packed for a point key (labels_multilod.hpp).
std::uint64_t pack(const Id g[3]) {
  std::uint64_t key = 0;
  for (int a = 0; a < 3; ++a) {
    if (g[a] < 0 || g[a] >= (Id{1} << kCellBits))
      throw LimitError("labels: a multilod output holds at most " + std::to_string((1 << kCellBits) - 2) +
                       " samples along an axis");
    key |= static_cast<std::uint64_t>(g[a]) << (kCellBits * a);
  }
  return key;
}

// The global key of every point of label part s (its keys are those of
// the label's box, surface nets, or of the view's padded grid, discrete MC);
// `offset`: the view's padded point 0 in the volume's padded grid.
std::vector<std::uint64_t> global_keys(const LabelSurface& part, const LabelVolume& vol, std::size_t s,
                                       LabelMethod method, const std::array<Id, 3>& offset) {
  std::vector<std::uint64_t> out(part.keys.size());
  Id lo[3], dims[3];
  for (int a = 0; a < 3; ++a) lo[a] = vol.box[s][a] - 1, dims[a] = vol.box[s][3 + a] - vol.box[s][a] + 3;
  const Id cx = dims[0] - 1, cy = dims[1] - 1, cells = cx * cy * (dims[2] - 1);
  for (std::size_t i = 0; i < out.size(); ++i) {
    const Id key = static_cast<Id>(part.keys[i]);
    Id g[3];
    if (method == LabelMethod::DiscreteMarchingCubes) {
      const Id p = key / 3;
      const Id at[3] = {p % vol.dims[0], (p / vol.dims[0]) % vol.dims[1], p / vol.nxy};
      for (int a = 0; a < 3; ++a) g[a] = at[a] + offset[a];
      out[i] = pack(g) << 2 | static_cast<std::uint64_t>(key % 3);
      continue;
    }
    const bool face = key >= 4 * cells;
    const Id fk = key - 4 * cells;
    const Id cell = face ? fk / 6 : key / 4;
    const Id sub = face ? 4 + fk % 6 : key % 4;  // face keys: 2 * (3 * cell + axis) + arc
    const Id at[3] = {cell % cx, (cell / cx) % cy, cell / (cx * cy)};
    for (int a = 0; a < 3; ++a) g[a] = lo[a] + at[a] + offset[a];
    out[i] = pack(g) << 4 | static_cast<std::uint64_t>(sub);
  }
  return out;
}

// Every selected label's closed surface as surface nets or discrete MC
// makes it, before smoothing, with the label table it was made from.
struct LabelParts {
  LabelOptions options;
  LabelVolume vol;
  std::vector<LabelSurface> parts;
};

LabelParts label_parts(const ImageGrid& view, const LabelOptions& options) {
  LabelParts out;
  out.options = options;
  out.options.per_label = true;
  const LabelOptions& opt = out.options;
  // Segment ids come from the label table, never a float32 field: exact.
  LabelVolume& vol = out.vol = detail::scan_labels(view, opt, detail::LabelRange::Int64Table);
  vol.per_label = true;
  vol.keep_keys = true;
  for (detail::LabelIndex l : vol.selected)
    if (vol.values[l] < 0)
      throw InputError("labels: label " + std::to_string(vol.values[l]) +
                       " is negative; Neuroglancer segment ids are unsigned");
  LabelStats stats;
  const std::pair<Id, Id> rows{0, vol.dims[2]};
  out.parts = opt.method == LabelMethod::SurfaceNets ? detail::surface_nets_rows(vol, true, rows, stats)
                                                     : detail::discrete_marching_cubes_rows(vol, rows, stats);
  return out;
}

// Label part s welded and smoothed as contour_labels(per_label) makes it,
// with global keys (the part itself is released).
SegmentSurface smoothed_segment(LabelParts& made, std::size_t s, const std::array<Id, 3>& offset) {
  const LabelOptions& opt = made.options;
  LabelSurface& part = made.parts[s];
  detail::smooth_label_surface(part, made.vol, opt.method, opt.smooth_iterations, opt.relaxation);
  SegmentSurface out;
  out.segment = static_cast<std::uint64_t>(made.vol.values[made.vol.selected[s]]);
  out.keys = global_keys(part, made.vol, s, opt.method, offset);
  out.points.assign(part.mesh.points.begin(), part.mesh.points.end());
  out.triangles.assign(part.mesh.connectivity.begin(), part.mesh.connectivity.end());
  part = LabelSurface{};
  return out;
}

std::array<Id, 3> chunk_index(const MultilodGrid& grid, Id id) {
  return {id % grid.chunks[0], (id / grid.chunks[0]) % grid.chunks[1], id / (grid.chunks[0] * grid.chunks[1])};
}

// The pieces of one segment in one chunk, every level.
std::vector<MultilodPiece> chunk_levels(const SegmentSurface& s, const MultilodGrid& grid, const std::array<Id, 3>& chunk,
                                     const std::uint32_t* triangles, Id count) {
  std::vector<MultilodPiece> out;
  out.push_back(detail::clip_to_chunk(s, grid, chunk, triangles, count));
  if (out.back().point_keys.empty()) return {};
  for (int lod = 1; lod < grid.lods; ++lod) out.push_back(detail::coarser_piece(out.back(), grid));
  return out;
}

void sort_pieces(std::vector<MultilodPiece>& pieces) {
  auto order = [](const MultilodPiece& p) { return std::tuple(p.segment, p.lod, p.chunk[2], p.chunk[1], p.chunk[0]); };
  std::sort(pieces.begin(), pieces.end(), [&](const MultilodPiece& a, const MultilodPiece& b) { return order(a) < order(b); });
  pieces.erase(std::remove_if(pieces.begin(), pieces.end(), [](const MultilodPiece& p) { return p.point_keys.empty(); }),
               pieces.end());
}

// The positions in `by_chunk` of the chunks wanted: every one, or `only`'s
// (none when the segment does not reach it).
std::vector<std::size_t> chunk_positions(const detail::ChunkTriangles& by_chunk, std::optional<Id> only) {
  std::vector<std::size_t> out;
  if (!only) {
    for (std::size_t c = 0; c < by_chunk.chunk.size(); ++c) out.push_back(c);
    return out;
  }
  const auto at = std::lower_bound(by_chunk.chunk.begin(), by_chunk.chunk.end(), *only);
  if (at != by_chunk.chunk.end() && *at == *only) out.push_back(static_cast<std::size_t>(at - by_chunk.chunk.begin()));
  return out;
}

// The pieces of every segment of `made` (`offset`: its view's padded point 0
// in the volume's padded grid) in every chunk, or in `only` (a chunk id).
// A segment's chunks start as soon as it is smoothed and cut, not after
// every segment is: no thread waits between the stages. A stage's error
// comes before a later stage's, each the first by index.
std::vector<MultilodPiece> chunk_pieces(LabelParts& made, const MultilodGrid& mg, const std::array<Id, 3>& offset,
                                        std::optional<Id> only) {
  const std::size_t n = made.parts.size();
  std::vector<SegmentSurface> segments(n);
  std::vector<detail::ChunkTriangles> by_chunk(n);
  std::vector<std::vector<std::size_t>> chunks(n);                   // per segment: positions in by_chunk
  std::vector<std::vector<std::vector<MultilodPiece>>> results(n);  // per segment, per chunk
  std::vector<std::exception_ptr> smoothing_errors(n), cutting_errors(n);
  std::vector<std::vector<std::exception_ptr>> chunk_errors(n);
  std::vector<std::atomic<std::size_t>> chunks_left(n);  // a segment's surface is released after its last chunk
  parallel::for_each_task_pipeline(
      static_cast<Id>(n),
      [&](Id s) -> Id {
        try {
          segments[s] = smoothed_segment(made, static_cast<std::size_t>(s), offset);
        } catch (...) {
          smoothing_errors[s] = std::current_exception();
          return 0;
        }
        try {
          detail::move_off_chunk_planes(segments[s], mg);
          by_chunk[s] = detail::triangles_by_chunk(segments[s], mg);
        } catch (...) {
          cutting_errors[s] = std::current_exception();
          return 0;
        }
        chunks[s] = chunk_positions(by_chunk[s], only);
        results[s].resize(chunks[s].size());
        chunk_errors[s].resize(chunks[s].size());
        chunks_left[s] = chunks[s].size();
        if (chunks[s].empty()) segments[s] = SegmentSurface{}, by_chunk[s] = detail::ChunkTriangles{};
        return static_cast<Id>(chunks[s].size());
      },
      [&](Id s, Id j) {  // a LimitError reaches the caller
        const detail::ChunkTriangles& in = by_chunk[s];
        const std::size_t c = chunks[s][j];
        try {
          results[s][j] = chunk_levels(segments[s], mg, chunk_index(mg, in.chunk[c]),
                                       in.triangles.data() + in.offsets[c], in.offsets[c + 1] - in.offsets[c]);
        } catch (...) {
          chunk_errors[s][j] = std::current_exception();
        }
        if (--chunks_left[s] == 0) segments[s] = SegmentSurface{}, by_chunk[s] = detail::ChunkTriangles{};
      });
  for (const auto* errors : {&smoothing_errors, &cutting_errors})
    for (const std::exception_ptr& e : *errors)
      if (e) std::rethrow_exception(e);
  for (const auto& errors : chunk_errors)
    for (const std::exception_ptr& e : errors)
      if (e) std::rethrow_exception(e);
  std::vector<MultilodPiece> pieces;
  for (auto& segment : results)
    for (auto& chunk : segment)
      for (auto& p : chunk) pieces.push_back(std::move(p));
  sort_pieces(pieces);
  return pieces;
}

// A copy of the samples [lo, lo + dims) of `grid`, placed in index space
// (sample i of the copy at lo + i).
ImageGrid crop(const ImageGrid& grid, const std::array<Id, 3>& lo, const std::array<Id, 3>& dims) {
  ImageGrid out;
  out.allocate(dims, grid.type);
  out.name = grid.name;
  const std::size_t size = scalar_size(grid.type);
  const auto* in = static_cast<const std::byte*>(grid.data());
  for (Id k = 0; k < dims[2]; ++k)
    for (Id j = 0; j < dims[1]; ++j)
      std::memcpy(out.bytes.data() + static_cast<std::size_t>((k * dims[1] + j) * dims[0]) * size,
                  in + static_cast<std::size_t>(lo[0] + grid.dims[0] * ((lo[1] + j) + grid.dims[1] * (lo[2] + k))) * size,
                  static_cast<std::size_t>(dims[0]) * size);
  for (int a = 0; a < 3; ++a) out.origin[a] = static_cast<double>(lo[a]), out.spacing[a] = 1.0;
  return out;
}

}  // namespace

MultilodGrid multilod_grid(const std::array<Id, 3>& dims, const MultilodOptions& options) {
  check_multilod_options(options);
  MultilodGrid g;
  g.chunk_shape = options.chunk_shape;
  g.lods = options.lods;
  g.vertex_quantization_bits = options.vertex_quantization_bits;
  for (int a = 0; a < 3; ++a) g.chunks[a] = (dims[a] + options.chunk_shape[a]) / options.chunk_shape[a];
  return g;
}

Id multilod_halo(const MultilodOptions& options) {
  // A point of the chunk's triangles is a cell outside at most; stencils
  // read 2 more samples.
  return detail::smoothing_reach(options.labels) + 4;
}

std::vector<MultilodPiece> multilod_pieces(const ImageGrid& grid, const MultilodOptions& options) {
  ImageGrid view;
  view.dims = grid.dims;
  view.type = grid.type;
  view.name = grid.name;
  view.external = static_cast<const std::byte*>(grid.data());
  LabelParts made = label_parts(view, options.labels);
  return chunk_pieces(made, multilod_grid(grid.dims, options), {0, 0, 0}, std::nullopt);
}

MultilodBox multilod_chunk_box(const std::array<Id, 3>& whole_dims, const MultilodOptions& options,
                               const std::array<Id, 3>& chunk) {
  const MultilodGrid mg = multilod_grid(whole_dims, options);
  for (int a = 0; a < 3; ++a)
    if (chunk[a] < 0 || chunk[a] >= mg.chunks[a])
      throw InputError("labels: chunk " + std::to_string(chunk[0]) + " " + std::to_string(chunk[1]) + " " +
                       std::to_string(chunk[2]) + " is outside the grid of " + std::to_string(mg.chunks[0]) + " x " +
                       std::to_string(mg.chunks[1]) + " x " + std::to_string(mg.chunks[2]) + " chunks");
  const Id halo = multilod_halo(options);
  MultilodBox box;
  for (int a = 0; a < 3; ++a) {
    box.lo[a] = std::max<Id>(static_cast<Id>(mg.plane(a, chunk[a])) - halo, 0);
    const Id hi = std::min<Id>(static_cast<Id>(mg.plane(a, chunk[a] + 1)) + halo, whole_dims[a] - 1);
    box.dims[a] = hi - box.lo[a] + 1;
  }
  return box;
}

std::vector<MultilodPiece> multilod_chunk_pieces(const ImageGrid& grid, const MultilodOptions& options,
                                              const std::array<Id, 3>& chunk) {
  const MultilodBox box = multilod_chunk_box(grid.dims, options, chunk);
  return multilod_box_pieces(crop(grid, box.lo, box.dims), grid.dims, box, options, chunk);
}

std::vector<MultilodPiece> multilod_box_pieces(const ImageGrid& box_samples, const std::array<Id, 3>& whole_dims,
                                            const MultilodBox& box, const MultilodOptions& options,
                                            const std::array<Id, 3>& chunk) {
  const MultilodGrid mg = multilod_grid(whole_dims, options);
  if (box_samples.dims != box.dims)
    throw InputError("labels: a chunk task's samples do not match its box (internal)");
  ImageGrid sub;  // a view of the box's samples in index space (sample i at box.lo + i)
  sub.dims = box.dims;
  sub.type = box_samples.type;
  sub.name = box_samples.name;
  sub.external = static_cast<const std::byte*>(box_samples.data());
  for (int a = 0; a < 3; ++a) sub.origin[a] = static_cast<double>(box.lo[a]), sub.spacing[a] = 1.0;
  const std::array<Id, 3>& lo = box.lo;
  LabelOptions opt = options.labels;
  if (!opt.labels.empty()) {  // the selected labels the sub-volume holds
    const std::vector<std::int64_t> held = detail::distinct_labels(sub);
    std::erase_if(opt.labels, [&](std::int64_t v) { return !std::binary_search(held.begin(), held.end(), v); });
    if (opt.labels.empty()) return {};
  }
  LabelParts made = label_parts(sub, opt);
  return chunk_pieces(made, mg, lo, chunk[0] + mg.chunks[0] * (chunk[1] + mg.chunks[1] * chunk[2]));
}

std::vector<std::array<Id, 3>> multilod_affected_chunks(const MultilodGrid& grid, const MultilodOptions& options,
                                                        const std::vector<std::array<Id, 3>>& changed) {
  const Id halo = multilod_halo(options);
  std::vector<std::array<Id, 3>> out;
  for (const auto& c : changed) {
    Id lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      if (c[a] < 0 || c[a] >= grid.chunks[a])
        throw InputError("labels: changed chunk " + std::to_string(c[0]) + " " + std::to_string(c[1]) + " " +
                         std::to_string(c[2]) + " is outside the grid of " + std::to_string(grid.chunks[0]) + " x " +
                         std::to_string(grid.chunks[1]) + " x " + std::to_string(grid.chunks[2]) + " chunks");
      const Id reach = 1 + halo / grid.chunk_shape[a];
      lo[a] = std::max<Id>(c[a] - reach, 0), hi[a] = std::min<Id>(c[a] + reach, grid.chunks[a] - 1);
    }
    for (Id z = lo[2]; z <= hi[2]; ++z)
      for (Id y = lo[1]; y <= hi[1]; ++y)
        for (Id x = lo[0]; x <= hi[0]; ++x) out.push_back({x, y, z});
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return std::tie(a[2], a[1], a[0]) < std::tie(b[2], b[1], b[0]);
  });
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace keymesh::generate
