// keymesh.labels_precomputed (a label volume in memory) and the tasks of
// keymesh.dask.labels_precomputed: Neuroglancer's multi-resolution meshes,
// as `keymesh labels IN -o DIR --format precomputed` writes them (one call;
// `--chunk I J K`; `--assemble`), through the same library calls
// (generate/labels/labels_multilod.hpp, io/neuroglancer_runs.hpp), so that
// the directories are byte-identical.
#include <filesystem>
#include <optional>

#include "common.hpp"
#include "keymesh/generate/labels/labels_multilod.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/neuroglancer_runs.hpp"

namespace keymesh::python {

namespace {

namespace ng = io::neuroglancer;

// The options the Python wrappers pass (python/keymesh/_precomputed.py), as a
// tuple: (method, labels, background, smooth, relaxation, lods, chunk_shape,
// sharded).
struct Precomputed {
  generate::MultilodOptions multilod;
  bool sharded = false;
};

Precomputed precomputed_of(const py::tuple& o) {
  if (o.size() != 8) throw py::value_error("labels_precomputed: the options tuple has 8 fields");
  Precomputed p;
  p.multilod.labels = label_options(o[0].cast<std::string>(), o[1].cast<std::vector<std::int64_t>>(),
                                    o[2].cast<std::int64_t>(), false, o[3].cast<int>(), o[4].cast<double>(), false);
  p.multilod.lods = o[5].cast<int>();
  p.multilod.chunk_shape = o[6].cast<std::array<Id, 3>>();
  p.sharded = o[7].cast<bool>();
  return p;
}

// The output directory's refusals, as the CLI's: a file, or a name a mesh
// file would have.
std::string output_dir(const std::string& path) {
  refuse_nul_path(path, "path");
  std::error_code ec;
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_directory(path, ec))
    throw py::value_error("path " + path + " is not a directory (labels_precomputed writes a directory)");
  const io::Format* format = io::format_by_name(path);
  if (format && format->kind == io::DataKind::Surface)
    throw py::value_error("path " + path + " names a mesh file; labels_precomputed writes a directory");
  return path;
}

// label_names: None (no names), a label table's path, or {id: name}; the
// background's entry left out, as the CLI leaves it out.
ng::SegmentNames segment_names(const py::object& names, std::int64_t background) {
  if (names.is_none()) return {};
  if (py::isinstance<py::str>(names) || py::hasattr(names, "__fspath__")) {
    const std::string path = py::str(py::module_::import("os").attr("fspath")(names));
    refuse_nul_path(path, "label_names");
    return ng::table_segment_names(path, background);
  }
  if (!py::isinstance<py::dict>(names))
    throw py::type_error("label_names must be None, a label table's path or a dict {segment id: name}, got " +
                         std::string(py::str(py::type::of(names).attr("__name__"))));
  ng::SegmentNames out;
  for (const auto& [id, name] : names.cast<py::dict>()) {
    const auto segment = integer_sequence(py::make_tuple(id), "label_names' ids")[0];
    if (segment < 0) throw py::value_error("label_names: segment ids are unsigned, got " + std::to_string(segment));
    out[static_cast<std::uint64_t>(segment)] = py::str(name).cast<std::string>();
  }
  if (background >= 0) out.erase(static_cast<std::uint64_t>(background));
  return out;
}

ImageGrid whole_header(const std::array<Id, 3>& whole, const py::object& spacing, const py::object& origin) {
  ImageGrid header;
  header.dims = whole;
  if (!spacing.is_none()) header.spacing = triple(spacing, "spacing");
  if (!origin.is_none()) header.origin = triple(origin, "origin");
  return header;
}

ng::MultilodLayout layout_of(const ImageGrid& header, const Precomputed& p) {
  const generate::MultilodGrid g = generate::multilod_grid(header.dims, p.multilod);
  return ng::multilod_layout(header, g.chunk_shape, g.chunks, g.grid_origin, g.lods, p.sharded);
}

py::dict counts_dict(const ng::PieceCounts& n) {
  py::dict d;
  d["segments"] = std::vector<std::uint64_t>(n.segments.begin(), n.segments.end());
  d["pieces"] = n.pieces;
  d["chunks_written"] = n.chunks;
  d["triangles_per_lod"] = n.triangles_per_lod;
  return d;
}

// The chunks to mesh: every chunk of the grid, or (`update`: the chunks an
// edit changed) those within the halo's reach of them, as --update picks them.
using Chunks = std::vector<std::array<Id, 3>>;

// update (None, or chunks (i, j, k)) read while the GIL is held.
std::optional<Chunks> changed_chunks(const py::object& update) {
  if (update.is_none()) return std::nullopt;
  return update.cast<Chunks>();
}

std::vector<std::array<Id, 3>> chunks_to_mesh(const generate::MultilodGrid& g, const Precomputed& p,
                                              const std::string& path, const std::optional<Chunks>& changed) {
  if (changed) {
    if (!std::filesystem::is_directory(std::filesystem::path(path) / "chunks"))
      throw InputError(path + ": no chunk store (" + path + "/chunks) of an earlier precomputed run to update");
    return generate::multilod_affected_chunks(g, p.multilod, *changed);
  }
  std::vector<std::array<Id, 3>> all;
  for (Id z = 0; z < g.chunks[2]; ++z)
    for (Id y = 0; y < g.chunks[1]; ++y)
      for (Id x = 0; x < g.chunks[0]; ++x) all.push_back({x, y, z});
  return all;
}

// `--update CHUNKS` in memory: the chunks within the halo's reach of the
// changed ones meshed again from the whole volume, and only the segments
// they held before or hold now rewritten (none: nothing to write), as the
// CLI's update_chunks does. The counts' segments are those rewritten.
ng::PieceCounts update_whole(const ImageGrid& grid, const Precomputed& p, const std::string& dir,
                             const Chunks& changed, const ng::SegmentNames& names) {
  const ng::MultilodLayout layout = layout_of(grid, p);
  const auto affected = chunks_to_mesh(generate::multilod_grid(grid.dims, p.multilod), p, dir, changed);
  ng::PieceCounts n;
  for (const auto& c : affected) {
    for (std::uint64_t s : ng::kept_segments(dir, ng::chunk_index(c))) n.segments.insert(s);
    std::vector<ng::ChunkPiece> pieces = ng::to_chunk_pieces(generate::multilod_chunk_pieces(grid, p.multilod, c));
    n.add(pieces);
    ng::write_chunk_pieces(dir, layout, ng::chunk_index(c), pieces);
    ++n.chunks;
  }
  if (!n.segments.empty())
    ng::assemble_multilod(dir, layout, std::vector<std::uint64_t>(n.segments.begin(), n.segments.end()), names);
  return n;
}

// The one call: every chunk meshed from the volume in memory, or with
// `update` (the chunks an edit changed) only those it can reach.
py::dict write_whole(const py::object& volume, const py::object& spacing, const py::object& origin,
                     const std::string& path, const py::tuple& options, const py::object& names, int threads,
                     const py::object& update) {
  check_threads(threads);
  const Precomputed p = precomputed_of(options);
  const std::string dir = output_dir(path);
  const ng::SegmentNames segment_names_ = segment_names(names, p.multilod.labels.background);
  const std::optional<Chunks> changed = changed_chunks(update);
  ArrayVolume view;
  const ImageGrid& grid = label_grid(volume, spacing, origin, view, "labels_precomputed");
  ng::PieceCounts n;
  run_released(threads, [&] {
    if (changed) {
      n = update_whole(grid, p, dir, *changed, segment_names_);
      return;
    }
    const ng::MultilodLayout layout = layout_of(grid, p);
    std::vector<ng::ChunkPiece> pieces = ng::to_chunk_pieces(generate::multilod_pieces(grid, p.multilod));
    n.add(pieces);
    n.chunks = static_cast<std::size_t>(layout.chunks[0]) * layout.chunks[1] * layout.chunks[2];
    ng::write_multilod_and_chunks(dir, layout, std::move(pieces), segment_names_);
  });
  return counts_dict(n);
}

// The chunk grid of a volume of `whole` samples and the box (the samples its
// task reads) of every chunk to mesh: {"chunks", "halo", "boxes": [(chunk, lo, dims)]}.
py::dict plan(const std::array<Id, 3>& whole, const py::tuple& options, const std::string& path,
              const py::object& update) {
  const Precomputed p = precomputed_of(options);
  output_dir(path);
  const generate::MultilodGrid g = generate::multilod_grid(whole, p.multilod);
  py::list boxes;
  for (const auto& c : chunks_to_mesh(g, p, path, changed_chunks(update))) {
    const generate::MultilodBox box = generate::multilod_chunk_box(whole, p.multilod, c);
    boxes.append(py::make_tuple(c, box.lo, box.dims));
  }
  py::dict d;
  d["chunks"] = g.chunks;
  d["chunk_shape"] = g.chunk_shape;
  d["halo"] = generate::multilod_halo(p.multilod);
  d["boxes"] = boxes;
  return d;
}

// `--chunk I J K`: the chunk's pieces from its box's samples (`box`, shape
// the box's dims, axis 0 = x) into path/chunks/.
// With `update`, "kept_segments" are the segments of the chunk's earlier
// pieces, read before they are replaced (--update rewrites those too).
py::dict write_chunk(const py::object& box_samples, const std::array<Id, 3>& whole, const std::array<Id, 3>& chunk,
                     const py::object& spacing, const py::object& origin, const std::string& path,
                     const py::tuple& options, int threads, bool update) {
  check_threads(threads);
  const Precomputed p = precomputed_of(options);
  const ImageGrid header = whole_header(whole, spacing, origin);
  const generate::MultilodBox box = generate::multilod_chunk_box(whole, p.multilod, chunk);
  ArrayVolume view = view_array_volume(box_samples, py::none(), py::none(), VolumeOrder::Fortran,
                                       {"labels_precomputed", 1, "a chunk's samples must be a 3-D numpy array", true});
  if (view.grid.dims != box.dims)
    throw py::value_error("labels_precomputed: chunk " + std::to_string(chunk[0]) + " " + std::to_string(chunk[1]) +
                          " " + std::to_string(chunk[2]) + " needs its box's " + std::to_string(box.dims[0]) + " x " +
                          std::to_string(box.dims[1]) + " x " + std::to_string(box.dims[2]) + " samples");
  ng::PieceCounts n;
  std::vector<std::uint64_t> kept;
  run_released(threads, [&] {
    std::vector<ng::ChunkPiece> pieces =
        ng::to_chunk_pieces(generate::multilod_box_pieces(view.grid, whole, box, p.multilod, chunk));
    n.add(pieces);
    n.chunks = 1;
    if (update) kept = ng::kept_segments(path, ng::chunk_index(chunk));
    ng::write_chunk_pieces(path, layout_of(header, p), ng::chunk_index(chunk), pieces);
  });
  py::dict d = counts_dict(n);
  if (update) d["kept_segments"] = kept;
  return d;
}

// `--assemble`: the output from every chunk's kept pieces; with `segments`
// (`--update`), only those segments rewritten (none: nothing to write).
void assemble(const std::array<Id, 3>& whole, const py::object& spacing, const py::object& origin,
              const std::string& path, const py::tuple& options, const py::object& names,
              const std::optional<std::vector<std::uint64_t>>& segments) {
  const Precomputed p = precomputed_of(options);
  const ImageGrid header = whole_header(whole, spacing, origin);
  const ng::SegmentNames segment_names_ = segment_names(names, p.multilod.labels.background);
  if (segments && segments->empty()) return;
  const std::vector<std::uint64_t> only = segments.value_or(std::vector<std::uint64_t>{});  // empty: all
  run_released(0, [&] { ng::assemble_multilod(path, layout_of(header, p), only, segment_names_); });
}

}  // namespace

void register_labels_precomputed(py::module_& m) {
  m.def("labels_precomputed", &write_whole, py::arg("volume"), py::arg("spacing"), py::arg("origin"), py::arg("path"),
        py::arg("options"), py::arg("label_names"), py::arg("threads") = 0, py::arg("update") = py::none(),
        "Neuroglancer multi-resolution meshes of a label volume; returns the counts. Use keymesh.labels_precomputed.");
  m.def("precomputed_segment_names", [](const py::object& names, std::int64_t background) {
    return segment_names(names, background);
  }, py::arg("label_names"), py::arg("background"),
        "label_names (None, a label table's path or a dict) as {id: name}. Use keymesh.dask.labels_precomputed.");
  m.def("precomputed_plan", &plan, py::arg("whole"), py::arg("options"), py::arg("path"), py::arg("update") = py::none(),
        "The chunk grid and every chunk's box. Use keymesh.dask.labels_precomputed.");
  m.def("precomputed_chunk", &write_chunk, py::arg("box"), py::arg("whole"), py::arg("chunk"), py::arg("spacing"),
        py::arg("origin"), py::arg("path"), py::arg("options"), py::arg("threads") = 1, py::arg("update") = false,
        "One chunk's pieces into path/chunks/. Use keymesh.dask.labels_precomputed.");
  m.def("precomputed_assemble", &assemble, py::arg("whole"), py::arg("spacing"), py::arg("origin"), py::arg("path"),
        py::arg("options"), py::arg("label_names"), py::arg("segments") = py::none(),
        "The output from every chunk's pieces. Use keymesh.dask.labels_precomputed.");
}

}  // namespace keymesh::python
