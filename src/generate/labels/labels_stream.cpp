// Label maps streamed in slabs: the three passes over the planes and the
// merge of the slabs' pieces by key (see keymesh/generate/labels/labels_stream.hpp).
#include "keymesh/core/retained_blocks.hpp"
#include "keymesh/generate/labels/labels_stream.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/core/free_storage.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "label_surface_bytes.hpp"
#include "label_volume.hpp"

namespace keymesh::generate {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Pieces of one surface, in face order, merged by point key: one KEY-REDUCE
// over their keys; the first piece holding a key gives the point (every
// piece computed it from the same samples).
detail::LabelSurface merge_by_key(const std::vector<const detail::LabelSurface*>& pieces) {
  detail::LabelSurface out;
  std::vector<std::uint64_t> keys;
  std::vector<std::size_t> base;  // first point of each piece in `keys`
  for (const detail::LabelSurface* p : pieces) {
    base.push_back(keys.size());
    keys.insert(keys.end(), p->keys.begin(), p->keys.end());
  }
  if (keys.size() > std::numeric_limits<std::uint32_t>::max())
    throw LimitError("labels --memory-limit: more than 2^32 - 1 points before merging");
  const std::uint64_t top = keys.empty() ? 0 : *std::max_element(keys.begin(), keys.end());
  const auto g = keyreduce::partition_sort(keys.data(), static_cast<Id>(keys.size()),
                                           parallel::bits_needed<std::uint64_t>(top), keyreduce::Order::Build);
  const Id unique = g.num_groups();
  out.keys.assign(g.unique_keys.begin(), g.unique_keys.end());  // ascending: the points' order
  // Surface nets' pieces carry cell centres (a slab without the surface
  // carries none).
  const bool centres = std::any_of(pieces.begin(), pieces.end(), [](auto* p) { return !p->cell_centre.empty(); });
  out.mesh.points.resize(static_cast<std::size_t>(3 * unique));
  out.junction.resize(static_cast<std::size_t>(unique));
  out.border_axes.resize(static_cast<std::size_t>(unique));
  out.cell_centre.resize(centres ? static_cast<std::size_t>(3 * unique) : 0);
  const bool coarse = std::any_of(pieces.begin(), pieces.end(), [](auto* p) { return !p->coarse.empty(); });
  out.coarse.resize(coarse ? static_cast<std::size_t>(unique) : 0);
  // Point j of the concatenation: its piece and index there.
  std::vector<std::uint32_t> piece_of(keys.size());
  for (std::size_t p = 0; p < pieces.size(); ++p)
    std::fill(piece_of.begin() + static_cast<std::ptrdiff_t>(base[p]),
              piece_of.begin() + static_cast<std::ptrdiff_t>(base[p] + pieces[p]->keys.size()),
              static_cast<std::uint32_t>(p));
  parallel::for_each(unique, [&](Id u) {
    const std::size_t first = g.order[static_cast<std::size_t>(g.offsets[u])];
    const detail::LabelSurface& s = *pieces[piece_of[first]];
    const std::size_t at = first - base[piece_of[first]];
    for (int a = 0; a < 3; ++a) out.mesh.points[3 * u + a] = s.mesh.points[3 * at + a];
    if (centres)
      for (int a = 0; a < 3; ++a) out.cell_centre[3 * u + a] = s.cell_centre[3 * at + a];
    out.junction[u] = s.junction[at];
    out.border_axes[u] = s.border_axes[at];
    if (coarse) out.coarse[u] = s.coarse[at];
  }, 1024);
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    const detail::LabelSurface& s = *pieces[p];
    const std::size_t c0 = out.mesh.connectivity.size();
    out.mesh.connectivity.resize(c0 + s.mesh.connectivity.size());
    parallel::for_each(static_cast<Id>(s.mesh.connectivity.size()), [&](Id c) {
      out.mesh.connectivity[c0 + static_cast<std::size_t>(c)] = g.index_map[base[p] + s.mesh.connectivity[c]];
    });
    out.pair.insert(out.pair.end(), s.pair.begin(), s.pair.end());
    out.ghost_face.insert(out.ghost_face.end(), s.ghost_face.begin(), s.ghost_face.end());
    for (const Field& f : s.mesh.cell_fields) {
      Field* to = nullptr;
      for (Field& h : out.mesh.cell_fields) to = h.name == f.name ? &h : to;
      if (!to) to = &out.mesh.cell_fields.emplace_back(Field{f.name, f.components, {}});
      to->values.insert(to->values.end(), f.values.begin(), f.values.end());
    }
  }
  return out;
}

std::vector<std::byte> counts_bytes(const detail::LabelCounts& c) {
  std::vector<std::byte> out(c.voxels.size() * sizeof(Id) + c.box.size() * sizeof(c.box[0]));
  // (memcpy only non-empty arrays: an empty one's data() may be null, UB even for 0 bytes)
  if (!c.voxels.empty()) std::memcpy(out.data(), c.voxels.data(), c.voxels.size() * sizeof(Id));
  if (!c.box.empty())
    std::memcpy(out.data() + c.voxels.size() * sizeof(Id), c.box.data(), c.box.size() * sizeof(c.box[0]));
  return out;
}

}  // namespace

struct LabelSlabs::Impl {
  // Slabs are held to a memory budget (or a rank's rows): no freed block kept.
  retained_blocks::KeepNothing within_the_budget;
  PlaneSource& source;
  LabelOptions options;
  std::pair<Id, Id> rows;
  Id nx = 0, ny = 0, nz = 0;
  Id rows_per_slab = 0;
  detail::LabelVolume vol;     // the label table; a window of planes per slab
  detail::LabelCounts counts;  // this process's planes (pass 2)
  std::vector<std::vector<detail::LabelSurface>> pieces;  // per slab, per part, in row order
  bool ghost_faces = false;  // generate_with_halo: every piece marks its triangles
  LabelStats st;
  LabelStreamStats ss;

  Impl(PlaneSource& s, const LabelOptions& o) : source(s), options(o) {}
  // The pieces held merged by key (part_points: each part's points, per label).
  detail::LabelSurface merged(std::vector<Id>* part_points);

  // The file planes this process reads in passes 1 and 2 (padded plane p is
  // file plane p - 1), and each step of the passes: slabs of planes.
  std::pair<Id, Id> own_file_planes() const {
    const Id b = std::max<Id>(rows.first, 1) - 1, e = std::min<Id>(rows.second, nz + 1) - 1;
    return {b, std::max(b, e)};
  }
  Id planes_per_read() const { return rows_per_slab + 2; }
  // Pass 3 over rows [k_begin, k_end) in slabs; `ghost`: the triangles are
  // another rank's (a halo).
  void generate_rows(Id k_begin, Id k_end, bool ghost) {
    for (Id k0 = k_begin; k0 < k_end; k0 += rows_per_slab) {
      const Id k1 = std::min(k0 + rows_per_slab, k_end);
      // The window: padded planes k0 - 1 .. k1 + 1 that exist; of those, the
      // file holds 1 .. nz.
      const Id w0 = std::max<Id>(k0 - 1, 0), w1 = std::min<Id>(k1 + 2, nz + 2);
      detail::allocate_window(vol, w0, w1 - w0);
      const Id f0 = std::max<Id>(w0, 1) - 1, f1 = std::min<Id>(w1, nz + 1) - 1;
      if (f1 > f0) detail::map_planes(vol, read(f0, f1 - f0), f0, nullptr);
      const auto t0 = Clock::now();
      pieces.push_back(options.method == LabelMethod::SurfaceNets
                           ? detail::surface_nets_rows(vol, options.per_label, {k0, k1}, st)
                           : detail::discrete_marching_cubes_rows(vol, {k0, k1}, st));
      if (options.method == LabelMethod::DiscreteMarchingCubes) st.generate += seconds_since(t0);
      if (ghost_faces)
        for (detail::LabelSurface& part : pieces.back()) part.ghost_face.assign(part.pair.size(), ghost ? 1 : 0);
      ++ss.slabs;
    }
  }
  ImageGrid read(Id first, Id count) {
    const auto t0 = Clock::now();
    const ImageGrid& head = source.header();
    ImageGrid g;
    g.spacing = head.spacing;
    g.origin = head.origin;
    g.name = head.name;
    g.allocate({nx, ny, count}, head.type);
    source.read_planes(first, count, g.bytes.data());
    ss.read += seconds_since(t0);
    return g;
  }
};

LabelSlabs::LabelSlabs(PlaneSource& source, const LabelOptions& options, std::size_t memory_limit)
    : LabelSlabs(source, options, memory_limit, {0, total_rows(source.header())}) {}

LabelSlabs::LabelSlabs(PlaneSource& source, const LabelOptions& options, std::size_t memory_limit,
                       std::pair<Id, Id> rows)
    : impl_(std::make_unique<Impl>(source, options)) {
  detail::check_label_options(options);
  const ImageGrid& head = source.header();
  detail::check_label_grid(head, options);
  Impl& m = *impl_;
  m.nx = head.dims[0], m.ny = head.dims[1], m.nz = head.dims[2];
  m.rows = rows;
  // A padded plane of samples and one of 16-bit label indices.
  const std::size_t plane = static_cast<std::size_t>(m.nx * m.ny) * scalar_size(head.type) +
                            static_cast<std::size_t>((m.nx + 2) * (m.ny + 2)) * sizeof(detail::LabelIndex);
  const Id fit = static_cast<Id>(memory_limit / plane);
  if (fit < 3)
    throw LimitError("labels --memory-limit " + std::to_string(memory_limit) + " bytes holds fewer than three " +
                     std::to_string(m.nx) + " x " + std::to_string(m.ny) + " planes of samples and label indices (" +
                     std::to_string(3 * plane) + " bytes needed)");
  m.rows_per_slab = std::clamp<Id>(fit - 2, 1, std::max<Id>(rows.second - rows.first, 1));
  m.ss.rows_per_slab = m.rows_per_slab;
  m.ss.slab_bytes = static_cast<std::size_t>(m.rows_per_slab + 2) * plane;
}

LabelSlabs::~LabelSlabs() = default;

std::vector<std::int64_t> LabelSlabs::distinct_labels() {
  Impl& m = *impl_;
  const auto t0 = Clock::now();
  std::vector<std::int64_t> values;
  const auto [b, e] = m.own_file_planes();
  for (Id f = b; f < e; f += m.planes_per_read())
    detail::merge_distinct(values, detail::distinct_labels(m.read(f, std::min(m.planes_per_read(), e - f))));
  m.st.scan += seconds_since(t0);
  return values;
}

void LabelSlabs::set_labels(const std::vector<std::vector<std::int64_t>>& all) {
  Impl& m = *impl_;
  std::vector<std::int64_t> values;
  for (const auto& v : all) detail::merge_distinct(values, v);
  m.vol = detail::label_table(m.source.header(), std::move(values), m.options);
  m.vol.window = true;
  m.vol.coarse_keys = m.options.coarsen;
  m.vol.per_label = m.options.per_label;
  m.st.distinct_labels = m.vol.distinct_in_grid;
  m.st.surfaces = static_cast<Id>(m.vol.selected.size());
}

std::vector<std::byte> LabelSlabs::count_labels() {
  Impl& m = *impl_;
  const auto t0 = Clock::now();
  m.counts.reset(static_cast<Id>(m.vol.values.size()));
  const auto [b, e] = m.own_file_planes();
  for (Id f = b; f < e; f += m.planes_per_read()) {
    const ImageGrid planes = m.read(f, std::min(m.planes_per_read(), e - f));
    detail::allocate_window(m.vol, f + 1, planes.dims[2]);
    detail::map_planes(m.vol, planes, f, &m.counts);
  }
  free_storage(m.vol.index);
  m.st.scan += seconds_since(t0);
  return counts_bytes(m.counts);
}

void LabelSlabs::set_counts(const std::vector<std::vector<std::byte>>& all) {
  Impl& m = *impl_;
  detail::LabelCounts total;
  const Id nl = static_cast<Id>(m.vol.values.size());
  total.reset(nl);
  const std::size_t expect = counts_bytes(total).size();
  for (const auto& bytes : all) {
    if (bytes.size() != expect)
      throw InputError("labels: a rank counted " + std::to_string(bytes.size()) + " bytes of labels, not " +
                       std::to_string(expect));
    detail::LabelCounts c;
    c.reset(nl);
    if (!c.voxels.empty()) std::memcpy(c.voxels.data(), bytes.data(), c.voxels.size() * sizeof(Id));
    if (!c.box.empty())
      std::memcpy(c.box.data(), bytes.data() + c.voxels.size() * sizeof(Id), c.box.size() * sizeof(c.box[0]));
    total.merge(c);
  }
  detail::set_boxes(m.vol, total);
}

void LabelSlabs::generate() {
  Impl& m = *impl_;
  m.generate_rows(m.rows.first, m.rows.second, false);
  free_storage(m.vol.index);
}

Id LabelSlabs::halo_rows(const LabelOptions& options) {
  return detail::smoothing_reach(options) + (options.coarsen ? 8 : 4);
}

void LabelSlabs::generate_with_halo(Id halo) {
  Impl& m = *impl_;
  m.ghost_faces = true;
  const Id first = std::max<Id>(m.rows.first - halo, 0), end = std::min<Id>(m.rows.second + halo, m.nz + 2);
  if (m.rows.first < m.rows.second) {  // a rank without rows has no piece
    m.generate_rows(first, m.rows.first, true);
    m.generate_rows(m.rows.first, m.rows.second, false);
    m.generate_rows(m.rows.second, end, true);
  }
  m.ss.halo_rows = (m.rows.first - first) + (end - m.rows.second);
  free_storage(m.vol.index);
}

std::vector<std::byte> LabelSlabs::pieces_bytes() const {
  std::vector<std::byte> out;
  detail::write_pieces(impl_->pieces, out);
  return out;
}

void LabelSlabs::add_pieces(const std::vector<std::byte>& bytes) { detail::read_pieces(bytes, impl_->pieces); }

detail::LabelSurface LabelSlabs::Impl::merged(std::vector<Id>* part_points) {
  const auto t0 = Clock::now();
  const std::size_t parts = pieces.empty() ? 0 : pieces[0].size();
  for (const auto& slab : pieces)
    if (slab.size() != parts) throw InputError("labels: the slabs hold different numbers of surfaces");
  // Per label (--per-label): each part merged on its own, appended in label
  // order. The network: one surface, its parts (discrete MC's labels) one
  // after the other, each part's slabs in row order.
  detail::LabelSurface surface;
  surface.quads = options.method == LabelMethod::SurfaceNets && !options.per_label;
  if (options.per_label) {
    std::vector<detail::LabelSurface> merged;
    for (std::size_t p = 0; p < parts; ++p) {
      std::vector<const detail::LabelSurface*> list;
      for (const auto& slab : pieces) list.push_back(&slab[p]);
      merged.push_back(merge_by_key(list));
      if (part_points) part_points->push_back(static_cast<Id>(merged.back().junction.size()));
    }
    detail::append_surfaces(merged, surface);
  } else {
    std::vector<const detail::LabelSurface*> list;
    for (std::size_t p = 0; p < parts; ++p)
      for (const auto& slab : pieces) list.push_back(&slab[p]);
    detail::LabelSurface merged = merge_by_key(list);
    merged.quads = surface.quads;
    surface = std::move(merged);
  }
  // Discrete MC always carries `label`, also with no surface at all.
  if (options.method == LabelMethod::DiscreteMarchingCubes && !surface.mesh.find_cell_field("label"))
    surface.mesh.cell_fields.push_back(Field{"label", 1, {}});
  pieces.clear();
  ss.merge = seconds_since(t0);
  st.weld += ss.merge;
  return surface;
}

SurfaceMesh LabelSlabs::finish(std::vector<std::uint64_t>* history_key) {
  Impl& m = *impl_;
  detail::LabelSurface surface = m.merged(nullptr);
  SurfaceMesh mesh = detail::finish_label_mesh(surface, m.vol, m.options, m.st);
  if (history_key) *history_key = std::move(surface.history_key);
  return mesh;
}

LabelPiece LabelSlabs::finish_piece() {
  Impl& m = *impl_;
  std::vector<Id> part_points;
  detail::LabelSurface surface = m.merged(&part_points);
  LabelPiece piece;
  piece.mesh = detail::finish_label_mesh(surface, m.vol, m.options, m.st);
  piece.ghost_face = std::move(surface.ghost_face);
  piece.history_key = std::move(surface.history_key);
  piece.segments = detail::point_rows(m.vol, m.options, surface.keys, part_points, piece.order_key, piece.row);
  return piece;
}

const LabelStats& LabelSlabs::stats() const { return impl_->st; }
const LabelStreamStats& LabelSlabs::stream_stats() const { return impl_->ss; }

SurfaceMesh contour_labels_streamed(PlaneSource& source, const LabelOptions& options, std::size_t memory_limit,
                                    LabelStats* stats, LabelStreamStats* stream_stats,
                                    std::vector<std::uint64_t>* history_key) {
  LabelSlabs slabs(source, options, memory_limit);
  slabs.set_labels({slabs.distinct_labels()});
  slabs.set_counts({slabs.count_labels()});
  slabs.generate();
  SurfaceMesh mesh = slabs.finish(history_key);
  if (stats) *stats = slabs.stats();
  if (stream_stats) *stream_stats = slabs.stream_stats();
  return mesh;
}

}  // namespace keymesh::generate
