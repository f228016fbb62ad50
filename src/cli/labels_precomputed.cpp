// keymesh labels IN -o DIR --format precomputed: Neuroglancer's
// multi-resolution meshes (generate/labels/labels_multilod.hpp cuts and
// coarsens the surfaces, io/neuroglancer.hpp writes them). Four routes:
//   one call           every chunk's pieces, kept under DIR/chunks/, and the output;
//   --chunk I J K      one chunk's pieces into DIR/chunks/ (a task; it holds only
//                      its box's planes where the format can be read by planes);
//   --assemble         the output from every chunk's kept pieces (after the tasks;
//                      with --memory-limit, in batches of segments of that size);
//   --update CHUNKS    the chunks an edit inside CHUNKS can reach recomputed,
//                      then the segments they held before or hold now rewritten.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <set>

#include "keymesh/core/error.hpp"
#include "keymesh/generate/labels/labels_multilod.hpp"
#include "keymesh/generate/labels/labels_stream.hpp"
#include "keymesh/io/label_table.hpp"
#include "keymesh/io/neuroglancer.hpp"
#include "keymesh/io/neuroglancer_runs.hpp"
#include "keymesh/io/plane_source.hpp"
#include "keymesh/io/volume_io.hpp"
#include "labels_job.hpp"

namespace keymesh::cli {

namespace {

namespace ng = io::neuroglancer;

generate::MultilodOptions multilod_options(const LabelsJob& job) {
  generate::MultilodOptions o;
  o.labels = job.options;
  o.chunk_shape = job.precomputed.chunk_shape;
  o.lods = job.precomputed.lods;
  return o;
}

// The segments' names: --label-names, else the label table beside the input
// (none: no segment_properties).
ng::SegmentNames segment_names(const LabelsJob& job) {
  const PrecomputedJob& pc = job.precomputed;
  return ng::table_segment_names(pc.label_names_given ? pc.label_names : io::label_table_beside(job.input),
                                 job.options.background);
}

using Counts = ng::PieceCounts;

// One call: every chunk's pieces kept (for a later --update), then the output.
Counts write_everything(const LabelsJob& job, const ImageGrid& grid, const ng::MultilodLayout& layout,
                        StageTimer& timer) {
  const auto o = multilod_options(job);
  std::vector<ng::ChunkPiece> pieces = ng::to_chunk_pieces(timer.run("labels", [&] {
    return naming_input(job, [&] { return generate::multilod_pieces(grid, o); });
  }));
  Counts n;
  n.add(pieces);
  n.chunks = static_cast<std::size_t>(layout.chunks[0]) * layout.chunks[1] * layout.chunks[2];
  timer.run("write", [&] { ng::write_multilod_and_chunks(job.output, layout, std::move(pieces), segment_names(job)); });
  return n;
}

// A chunk task's or the final step's input: the volume read plane by plane
// where its format allows (raw, NRRD, NIfTI, VTI, gzip-compressed ones too,
// Zarr, DICOM: io/plane_source.hpp), so that a task holds only the planes of
// its box and the final step reads the header alone; null otherwise (read
// whole).
std::unique_ptr<PlaneSource> input_planes(const LabelsJob& job, const io::RawOptions* raw) {
  if (!job.precomputed.chunk_given && !job.precomputed.assemble) return nullptr;
  try {
    return io::open_volume_planes(job.input, raw);
  } catch (const InputError&) {
    return nullptr;  // read_volume reads it whole, or says what is wrong with it
  }
}

// The box's samples: its planes read, their rows cropped to the box.
ImageGrid read_box(PlaneSource& planes, const generate::MultilodBox& box) {
  const ImageGrid& h = planes.header();
  const std::size_t size = scalar_size(h.type);
  const std::size_t row = static_cast<std::size_t>(h.dims[0]) * size, plane = row * static_cast<std::size_t>(h.dims[1]);
  std::vector<std::byte> slab(plane * static_cast<std::size_t>(box.dims[2]));
  planes.read_planes(box.lo[2], box.dims[2], slab.data());
  ImageGrid out;
  out.allocate(box.dims, h.type);
  out.name = h.name;
  const std::size_t out_row = static_cast<std::size_t>(box.dims[0]) * size;
  for (Id k = 0; k < box.dims[2]; ++k)
    for (Id j = 0; j < box.dims[1]; ++j)
      std::memcpy(out.bytes.data() + static_cast<std::size_t>(k * box.dims[1] + j) * out_row,
                  slab.data() + static_cast<std::size_t>(k) * plane + static_cast<std::size_t>(box.lo[1] + j) * row +
                      static_cast<std::size_t>(box.lo[0]) * size,
                  out_row);
  return out;
}

// --chunk I J K: the chunk's pieces from its box and halo (`planes`: read
// just those; else `grid` holds the whole volume).
Counts write_one_chunk(const LabelsJob& job, const ImageGrid& grid, PlaneSource* planes,
                       const ng::MultilodLayout& layout, StageTimer& timer, std::uint64_t& samples_read) {
  const std::array<Id, 3> c = job.precomputed.chunk;
  const auto o = multilod_options(job);
  ImageGrid box_samples;
  const generate::MultilodBox box = naming_input(job, [&] { return generate::multilod_chunk_box(grid.dims, o, c); });
  if (planes) {
    check_labels_memory(job, grid, {0, box.dims[2] + 2});
    box_samples = timer.run("read", [&] { return read_box(*planes, box); });
    samples_read = static_cast<std::uint64_t>(grid.dims[0] * grid.dims[1] * box.dims[2]);
  }
  std::vector<ng::ChunkPiece> pieces = ng::to_chunk_pieces(timer.run("labels", [&] {
    return naming_input(job, [&] {
      return planes ? generate::multilod_box_pieces(box_samples, grid.dims, box, o, c)
                    : generate::multilod_chunk_pieces(grid, o, c);
    });
  }));
  Counts n;
  n.add(pieces);
  n.chunks = 1;
  timer.run("write", [&] { ng::write_chunk_pieces(job.output, layout, ng::chunk_index(c), pieces); });
  return n;
}

// --update CHUNKS: the reachable chunks recomputed, their segments rewritten.
Counts update_chunks(const LabelsJob& job, const ImageGrid& grid, const ng::MultilodLayout& layout,
                     StageTimer& timer) {
  if (!std::filesystem::is_directory(std::filesystem::path(job.output) / "chunks"))
    throw InputError(job.output + ": no chunk store (" + job.output +
                     "/chunks) of an earlier --format precomputed run to update");
  const auto o = multilod_options(job);
  const auto affected = naming_input(job, [&] {
    return generate::multilod_affected_chunks(generate::multilod_grid(grid.dims, o), o, job.precomputed.update);
  });
  Counts n;
  for (const auto& c : affected) {
    for (std::uint64_t s : ng::kept_segments(job.output, ng::chunk_index(c))) n.segments.insert(s);
    std::vector<ng::ChunkPiece> pieces = ng::to_chunk_pieces(timer.run("labels", [&] {
      return naming_input(job, [&] { return generate::multilod_chunk_pieces(grid, o, c); });
    }));
    n.add(pieces);
    timer.run("write", [&] { ng::write_chunk_pieces(job.output, layout, ng::chunk_index(c), pieces); });
    ++n.chunks;
  }
  timer.run("assemble", [&] {
    if (!n.segments.empty())
      ng::assemble_multilod(job.output, layout, std::vector<std::uint64_t>(n.segments.begin(), n.segments.end()),
                            segment_names(job));
  });
  return n;
}

}  // namespace

int run_labels_precomputed(const LabelsJob& job) {
  StageTimer timer;
  const PrecomputedJob& pc = job.precomputed;
  const io::RawOptions* raw = job.raw_given ? &job.raw : nullptr;
  const std::unique_ptr<PlaneSource> planes = input_planes(job, raw);
  // With planes, `grid` is the header only (no samples): the task reads its box.
  const ImageGrid grid = timer.run("read", [&] { return planes ? planes->header() : io::read_volume(job.input, raw); });
  std::uint64_t samples_read = planes ? 0 : static_cast<std::uint64_t>(grid.num_points());
  std::size_t assemble_batches = 0;
  if (!planes) check_labels_memory(job, grid, {0, generate::LabelSlabs::total_rows(grid)});
  const auto o = multilod_options(job);
  const generate::MultilodGrid g = naming_input(job, [&] { return generate::multilod_grid(grid.dims, o); });
  const ng::MultilodLayout layout = ng::multilod_layout(grid, g.chunk_shape, g.chunks, g.grid_origin, g.lods, pc.sharded);
  Counts n;
  const char* route = "one call";
  if (pc.chunk_given) {
    n = write_one_chunk(job, grid, planes.get(), layout, timer, samples_read), route = "chunk";
  } else if (pc.assemble) {
    timer.run("assemble", [&] {
      assemble_batches = ng::assemble_multilod(job.output, layout, {}, segment_names(job), job.memory_limit);
    });
    route = "assemble";
  } else if (!pc.update.empty()) {
    n = update_chunks(job, grid, layout, timer), route = "update";
  } else {
    n = write_everything(job, grid, layout, timer);
  }
  if (!job.common.quiet)
    std::fprintf(stderr, "keymesh: %s: %zu segments, %zu pieces of %zu chunks, %d levels of detail -> %s\n", route,
                 n.segments.size(), n.pieces, n.chunks, pc.lods, printable(job.output).c_str());
  nlohmann::json r;
  r.update({{"input", job.input}, {"output", job.output}, {"format", "precomputed"}, {"route", route},
            {"method", job.method}, {"smooth", job.options.smooth_iterations}, {"lods", pc.lods},
            {"chunk_shape", g.chunk_shape}, {"chunks", g.chunks}, {"halo", generate::multilod_halo(o)},
            {"sharded", pc.sharded}, {"segments", n.segments.size()}, {"pieces", n.pieces},
            {"chunks_written", n.chunks}, {"triangles_per_lod", n.triangles_per_lod}, {"dims", grid.dims},
            {"samples_read", samples_read}});
  if (pc.assemble) r["assemble_batches"] = assemble_batches;
  finish_report(job.common, std::move(r), job.threads, timer, PeakRss::Include);
  return 0;
}

}  // namespace keymesh::cli
