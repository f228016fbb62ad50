// keymesh labels IN -o OUT [...]: welded surfaces of a label map.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <memory>

#include "command.hpp"
#include "labels_job.hpp"
#include "raw_input.hpp"
#include "keymesh/backend/labels.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/generate/labels/labels.hpp"
#include "keymesh/generate/labels/labels_stream.hpp"
#include "keymesh/generate/report_fields.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/plane_source.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

namespace {

struct LabelsCli {
  std::string input, output;
  std::string method = "surfacenets";
  std::vector<long long> labels;
  long long background = 0;
  bool per_label = false;
  int smooth = 16;
  double relaxation = 0.5;
  std::string memory_limit;  // stream the volume in slabs
  bool coarsen = false;
  bool history = false;  // history_key and history_t per point (.vtp, .pvtp pieces)
  RawInputCli raw_input;
  CommonOptions common;
  // --format precomputed and its options (labels_precomputed.cpp).
  std::string format;
  int lods = 3;
  std::vector<long long> chunk_shape{32, 32, 32};
  bool sharded = false;
  std::vector<long long> chunk;
  bool assemble = false;
  std::string update;
  std::string label_names;
  std::vector<Option*> precomputed_only;  // refused without --format precomputed
};

LabelsJob job_of(const LabelsCli& o) {
  LabelsJob job;
  job.input = o.input;
  job.output = o.output;
  job.method = o.method;
  job.raw_given = o.raw_input.given();
  if (job.raw_given) job.raw = o.raw_input.options();
  generate::LabelOptions& opt = job.options;
  opt.method = generate::parse_option<generate::LabelMethod>(o.method);
  opt.labels.assign(o.labels.begin(), o.labels.end());
  opt.background = o.background;
  opt.per_label = o.per_label;
  opt.smooth_iterations = o.smooth;
  opt.relaxation = o.relaxation;
  opt.coarsen = o.coarsen;
  opt.history = o.history;
  if (!o.memory_limit.empty()) parse_size(o.memory_limit, job.memory_limit);  // checked by its validator
  job.common = o.common;
  PrecomputedJob& pc = job.precomputed;
  pc.on = o.format == "precomputed";
  pc.lods = o.lods;
  for (int a = 0; a < 3; ++a) pc.chunk_shape[a] = o.chunk_shape[static_cast<std::size_t>(a)];
  pc.sharded = o.sharded;
  pc.label_names = o.label_names;
  pc.label_names_given = !o.label_names.empty();
  pc.chunk_given = !o.chunk.empty();
  for (std::size_t a = 0; a < o.chunk.size() && a < 3; ++a) pc.chunk[a] = o.chunk[a];
  pc.assemble = o.assemble;
  return job;
}

// --update CHUNKS: "I,J,K;I,J,K..." or @FILE (one "I J K" or "I,J,K" a
// line, # comments). False, with `why`, for anything else.
bool parse_chunk_list(const std::string& text, std::vector<std::array<Id, 3>>& out, std::string& why) {
  std::string list = text;
  if (!text.empty() && text[0] == '@') {
    std::ifstream in(text.substr(1));
    if (!in) return why = "cannot read the chunk list " + text.substr(1), false;
    std::ostringstream all;
    for (std::string line; std::getline(in, line);) all << line.substr(0, line.find('#')) << ';';
    list = all.str();
  }
  std::istringstream items(list);
  for (std::string item; std::getline(items, item, ';');) {
    std::replace(item.begin(), item.end(), ',', ' ');
    std::istringstream in(item);
    std::array<Id, 3> c{};
    std::string rest;
    if (item.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (!(in >> c[0] >> c[1] >> c[2]) || (in >> rest))
      return why = "'" + item + "' is not a chunk I,J,K", false;
    out.push_back(c);
  }
  if (out.empty()) return why = "'" + text + "' names no chunk", false;
  return true;
}

// The options --format precomputed refuses, and those only it takes; the
// exit code (0, or 2 after the message).
int check_precomputed(const LabelsCli& o, LabelsJob& job) {
  auto refuse = [](const std::string& why) {
    std::fprintf(stderr, "keymesh labels: %s\n", printable(why).c_str());
    return 2;
  };
  if (o.format.empty()) {
    for (const Option* opt : o.precomputed_only)
      if (opt->count() > 0) return refuse(opt->get_name() + " needs --format precomputed");
    return 0;
  }
  const std::string not_here = " does not apply to --format precomputed";
  if (o.coarsen) return refuse("--coarsen" + not_here + " (its levels of detail coarsen)");
  if (!o.memory_limit.empty() && !o.assemble)
    return refuse("--memory-limit" + not_here + " but to --assemble (run --chunk tasks instead)");
  if (distributed::size() > 1) return refuse("mpirun" + not_here + " (run --chunk tasks instead)");
  if ((o.chunk.empty() ? 0 : 1) + (o.assemble ? 1 : 0) + (o.update.empty() ? 0 : 1) > 1)
    return refuse("--chunk, --assemble and --update exclude each other");
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(o.output, ec) && !fs::is_directory(o.output, ec))
    return refuse("-o " + o.output + " is not a directory (--format precomputed writes a directory)");
  if (is_mesh_path(o.output)) return refuse("-o " + o.output + " names a mesh file; --format precomputed writes a directory");
  std::string why;
  if (!o.update.empty() && !parse_chunk_list(o.update, job.precomputed.update, why)) return refuse("--update: " + why);
  return 0;
}

// --history's usage errors (exit 2, said by rank 0): the output must hold
// a UInt64 point array (.vtp; .pvtp pieces under mpirun), the points must
// each come from one element (no --coarsen).
int refuse_history_usage(const LabelsCli& o) {
  if (!o.history) return 0;
  std::string why;
  const std::string ext = io::file_extension(o.output);
  if (o.format == "precomputed")
    why = "--history does not apply to --format precomputed (Neuroglancer's meshes hold no point arrays)";
  else if (o.coarsen)
    why = "--history with --coarsen: a coarsened point merges the points of several cells or edges, so it has no "
          "one element";
  else if (ext != ".vtp" && !(ext == ".pvtp" && distributed::launched_by_mpi()))
    why = "--history writes history_key as UInt64, which only .vtp holds (" + o.output + ")";
  if (why.empty()) return 0;
  if (distributed::rank() == 0) std::fprintf(stderr, "keymesh labels: %s (docs/HISTORY.md)\n", printable(why).c_str());
  return 2;
}

Id held_rows(const ImageGrid& header) { return generate::LabelSlabs::total_rows(header); }

// --memory-limit: the volume streamed in slabs of z-planes. Returns the
// mesh; `r` gets the keys only this path reports.
SurfaceMesh labels_streamed(const LabelsJob& job, StageTimer& timer, generate::LabelStats& stats, nlohmann::json& r,
                            std::vector<std::uint64_t>& history_key) {
  auto source = io::open_volume_planes(job.input, job.raw_given ? &job.raw : nullptr);
  check_labels_memory(job, source->header(), {0, held_rows(source->header())});
  generate::LabelStreamStats ss;
  SurfaceMesh mesh = timer.run("labels", [&] {
    return naming_input(job, [&] {
      return generate::contour_labels_streamed(*source, job.options, job.memory_limit, &stats, &ss, &history_key);
    });
  });
  timer.add("read", ss.read);
  r["dims"] = source->header().dims;
  r["scalar_type"] = scalar_type_name(source->header().type);
  r["memory_limit"] = job.memory_limit;
  r["stream"] = {{"slabs", ss.slabs}, {"rows_per_slab", ss.rows_per_slab}, {"slab_bytes", ss.slab_bytes},
                 {"read", ss.read}, {"merge", ss.merge}};
  return mesh;
}

// The volume read whole, contoured on the backend --backend names.
SurfaceMesh labels_in_memory(const LabelsJob& job, StageTimer& timer, Progress& progress,
                             generate::LabelStats& stats, nlohmann::json& r, std::vector<std::uint64_t>& history_key) {
  progress.say("reading " + job.input);
  const io::RawOptions* raw = job.raw_given ? &job.raw : nullptr;
  const ImageGrid grid = timer.run("read", [&] { return io::read_volume(job.input, raw); });
  check_labels_memory(job, grid, {0, held_rows(grid)});
  progress.enable_if(grid.num_points() > (1ll << 25));
  r["dims"] = grid.dims;
  r["scalar_type"] = scalar_type_name(grid.type);
  return timer.run("labels", [&] {
    const auto backend = generate::parse_option<generate::Backend>(job.common.backend);
    return naming_input(job, [&] { return backend::contour_labels(grid, job.options, backend, &stats, &history_key); });
  });
}

// One process: the volume in memory (on --backend's device), or streamed
// with --memory-limit (the CPU only).
int run_labels(const LabelsJob& job) {
  if (job.memory_limit)
    if (int rc = require_cpu_backend(job.common, "streaming (--memory-limit)")) return rc;
  StageTimer timer;
  Progress progress(job.common.quiet, file_size(job.input) > (64ll << 20));
  generate::LabelStats stats;
  nlohmann::json r;
  std::vector<std::uint64_t> history_key;
  const SurfaceMesh mesh = job.memory_limit ? labels_streamed(job, timer, stats, r, history_key)
                                            : labels_in_memory(job, timer, progress, stats, r, history_key);
  progress.say("writing " + job.output);
  write_labels_outputs(job, mesh, stats, std::move(r), timer, history_key);
  return 0;
}

}  // namespace

void check_labels_memory(const LabelsJob& job, const ImageGrid& header, std::pair<Id, Id> rows) {
  const auto nx = static_cast<std::uint64_t>(header.dims[0]), ny = static_cast<std::uint64_t>(header.dims[1]);
  // A padded row: a plane of samples and a plane of label indices with a border of one.
  const std::uint64_t row = saturating_add(saturating_mul(saturating_mul(nx, ny), scalar_size(header.type)),
                                           saturating_mul(saturating_mul(nx + 2, ny + 2), 2));
  const auto count = static_cast<std::uint64_t>(std::max<Id>(rows.second - rows.first, 0));
  std::uint64_t bytes = saturating_mul(row, count);
  const bool slab = job.memory_limit && job.memory_limit < bytes;
  if (slab) bytes = job.memory_limit;
  check_memory(job.common, bytes,
               job.input + ": labels: " +
                   (slab ? std::string("a --memory-limit slab of samples and label indices")
                         : "the samples and label indices of " + std::to_string(count) + " planes"));
}

void write_labels_outputs(const LabelsJob& job, const SurfaceMesh& mesh, const generate::LabelStats& stats,
                          nlohmann::json r, StageTimer& timer, const std::vector<std::uint64_t>& history_key) {
  const std::string ext = std::filesystem::path(job.output).extension().string();
  if (ext != ".vtp" && ext != ".ply" && !job.common.quiet)
    std::fprintf(stderr, "keymesh: warning: %s: %s files have no cell data; boundary_labels is not written "
                         "(use .vtp or .ply)\n", printable(job.output).c_str(),
                 printable(ext).c_str());
  timer.run("write", [&] {
    if (job.options.history) io::write_vtp(mesh, job.output, nullptr, nullptr, {{"history_key", &history_key}});
    else io::write_mesh(mesh, job.output);
  });
  if (!job.common.quiet)
    std::fprintf(stderr, "keymesh: %lld labels, %lld points, %lld triangles -> %s\n",
                 static_cast<long long>(stats.surfaces), static_cast<long long>(mesh.num_points()),
                 static_cast<long long>(mesh.num_cells()), printable(job.output).c_str());
  if (job.common.report_path.empty()) return;
  const generate::LabelOptions& opt = job.options;
  r.update({{"input", job.input}, {"output", job.output}, {"method", job.method}, {"per_label", opt.per_label},
            {"background", opt.background}, {"smooth", opt.smooth_iterations}, {"relaxation", opt.relaxation},
            {"coarsen", opt.coarsen}, {"history", opt.history}, {"distinct_labels", stats.distinct_labels},
            {"labels_extracted", stats.surfaces}, {"points", mesh.num_points()}, {"cells", mesh.num_cells()},
            {"threads", job.threads}, {"backend", job.common.backend}});
  // -1: not known (a gathered run under mpirun: no rank held the whole soup,
  // and each rank's guard also smoothed its halo rows).
  if (stats.soup_corners >= 0) r["soup_points"] = stats.soup_corners;
  if (stats.guard_shortened >= 0) r["guard_shortened"] = stats.guard_shortened;
  if (opt.coarsen) {
    if (stats.triangles_before_coarsening >= 0) r["triangles_before"] = stats.triangles_before_coarsening;
    r["triangles_after"] = mesh.num_cells();
  }
  nlohmann::json pairs = nlohmann::json::array();
  for (const auto& p : timer.run("count", [&] { return generate::label_pair_counts(mesh); }))
    pairs.push_back({{"labels", {p.first, p.second}}, {"points", p.points}, {"faces", p.faces}});
  r["pairs"] = pairs;
  auto seconds = timer.seconds();
  generate::visit_stage_seconds(stats, into(seconds["labels_stages"]));
  r["seconds"] = seconds;
  r["peak_rss_mib"] = peak_rss_mib();
  write_report(job.common.report_path, r);
}

namespace {

void add_precomputed_options(Subcommand& cmd, LabelsCli& o) {
  cmd.add_option("--format", o.format,
                 "output format: omitted, a mesh file named by -o's extension; precomputed: -o is a directory of "
                 "Neuroglancer multi-resolution meshes (neuroglancer_multilod_draco), one segment per label (its "
                 "closed surface, as --per-label), cut into chunks with --lods levels of detail; DIR/chunks keeps "
                 "every chunk's pieces for --chunk tasks, --assemble and --update")
      ->check(member_of({"precomputed"}));
  o.precomputed_only = {
      cmd.add_option("--lods", o.lods,
                     "levels of detail (default 3): level k merges each chunk's inner points to the grid of spacing "
                     "2^k (points on its faces kept as they are, so neighbouring chunks agree on them), splitting "
                     "back merges whose triangles would cross")
          ->check(in_range(1, 20)),
      cmd.add_option("--chunk-shape", o.chunk_shape,
                     "samples per lod-0 chunk along x y z (default 32 32 32, at least 2); chunk (i, j, k) covers "
                     "sample coordinates -1 + (i, j, k) * shape to -1 + (i + 1, j + 1, k + 1) * shape")
          ->expected(3)
          ->check(in_range(2LL, 1LL << 20)),
      cmd.add_flag("--sharded", o.sharded,
                   "the sharded layout (neuroglancer_uint64_sharded_v1): a few files for many segments"),
      cmd.add_option("--chunk", o.chunk,
                     "a chunk task: mesh chunk I J K only (from its box and a halo of samples around it) into "
                     "DIR/chunks; run --assemble once every chunk is done (the output equals one call's)")
          ->expected(3)
          ->check(non_negative()),
      cmd.add_flag("--assemble", o.assemble,
                   "the final step after the --chunk tasks: write DIR's meshes from every chunk's pieces in DIR/chunks"),
      cmd.add_option("--update", o.update,
                     "re-mesh an edit: IN differs from the earlier run's volume only inside CHUNKS ('I,J,K;I,J,K' or "
                     "@FILE with one 'I J K' a line); recomputes the chunks the edit can reach and rewrites the "
                     "segments they held or hold in DIR (needs its DIR/chunks); equal to a full run on IN"),
      cmd.add_option("--label-names", o.label_names,
                     "a label table, one 'ID NAME' a line (whitespace-separated; further columns, blank lines and "
                     "lines starting with # ignored): the segments' names, written as segment_properties/ "
                     "(default: IN.txt, or IN without .gz + .txt, when such a file is beside the input, as "
                     "MRIcron's atlases ship)")};
}

void add_labels_options(Subcommand& cmd, LabelsCli& o) {
  cmd.description("surfaces of a label map (segmentation): surface nets or discrete marching cubes, welded by keys");
  cmd.add_option("input", o.input,
                 "integer volume (uint8 int8 uint16 int16 int32 uint32 int64 uint64): " + io::accepted_volumes(false))
      ->required();
  cmd.add_option("-o,--output", o.output,
                 "output mesh (" + io::extensions_of(io::DataKind::Surface, true) +
                     "): .vtp (CellData) and .ply (face properties) keep the cell fields boundary_labels (and label), "
                     "the others drop them; under mpirun -np P, OUT.pvtp: every rank writes its own piece "
                     "(OUT_<rank>.vtp, GlobalPointIds, ghost cells) and rank 0 the index, nothing gathered; "
                     "any other file is gathered on rank 0")
      ->required();
  cmd.add_option("--method", o.method,
                 "surfacenets (a point per cell of mixed labels, a quad per edge between two labels, every "
                 "interface once; default) or discrete-mc (each label's marching cubes at edge midpoints, "
                 "as vtkDiscreteFlyingEdges3D)")
      ->check(one_of<generate::LabelMethod>());
  cmd.add_option("--labels", o.labels, "labels to extract, e.g. 3,17 (default: every label but the background); "
                                        "the others count as background")
      ->delimiter(',');
  cmd.add_option("--background", o.background, "the background label (default 0)");
  cmd.add_flag("--per-label", o.per_label,
               "each label's closed surface with its own points (cell field label), instead of one network");
  cmd.add_option("--smooth", o.smooth,
                 "smoothing iterations (default 16; 0 = off): constrained to each point's cell for surface nets, "
                 "Taubin for discrete-mc")
      ->check(non_negative());
  cmd.add_option("--relaxation", o.relaxation, "smoothing relaxation factor in (0, 1] (default 0.5)")
      ->check(in_range(1e-9, 1.0));
  cmd.add_flag("--coarsen", o.coarsen,
               "after smoothing, merge the points of each 2x2x2 block of cells (surfacenets) or nearest grid "
               "point (discrete-mc), averaging positions; faces that collapse are dropped, label pairs kept; "
               "every label's surface stays closed, not always 2-manifold");
  cmd.add_flag("--history", o.history,
               "per point, where it came from (docs/HISTORY.md): point arrays history_key (UInt64, in the grid "
               "padded with one sample all round, p = i + 1 + (nx + 2) * (j + 1 + (ny + 2) * (k + 1)) for sample "
               "(i, j, k): discrete-mc the edge 3 * p + axis, surfacenets 16 * p + slot, p the cell's first corner, "
               "slot its loop or face point) and history_t (Float32: 0.5, the edge's midpoint or the cell's centre); "
               "the unsmoothed point's, whatever --smooth; .vtp output (.pvtp pieces under mpirun), not with "
               "--coarsen or --format precomputed");
  o.raw_input.add_options(cmd, "uint8 int8 uint16 int16 int32 uint32 int64 uint64");
  cmd.add_option("--memory-limit", o.memory_limit,
                 "stream the input volume in slabs of z-planes holding at most SIZE bytes of samples and 16-bit "
                 "label indices (e.g. 256M); the surfaces are merged by key, then smoothed and written whole "
                 "(not streamed: the output mesh); byte-identical to one in-memory run; " +
                     io::accepted_plane_sources() + "; under mpirun -np P each rank streams its own rows; with "
                     "--format precomputed --assemble: the chunk pieces held at once (segments written in batches, "
                     "the same bytes)")
      ->check(size_validator());
  add_precomputed_options(cmd, o);
  add_common_options(cmd, o.common);
}

// One process (run_labels), or under mpirun -np P each rank its rows. The
// GPU runs the one-process, in-memory path; the others refuse --backend cuda
// by name.
int run_labels_command(const LabelsCli& o, CommandRun& run) {
  LabelsJob job = job_of(o);
  job.threads = run.threads();
  if (int rc = refuse_history_usage(o)) return rc;
  if (int rc = check_precomputed(o, job)) return rc;
  if (job.precomputed.on) {
    if (int rc = require_cpu_backend(o.common, "--format precomputed")) return rc;
    return run_labels_precomputed(job);
  }
  // One rank under mpirun writing .pvtp is the pieces path too (a piece and
  // its index), so a scaling series starts at -np 1 with the same files.
  const bool pieces = job.output.size() >= 5 && job.output.compare(job.output.size() - 5, 5, ".pvtp") == 0;
  if (distributed::size() > 1 || (pieces && distributed::launched_by_mpi())) {
    if (int rc = require_cpu_backend(o.common, "labels under mpirun")) return rc;
    return run_distributed_labels(job);
  }
  return run_labels(job);
}

Register reg{make_run_command("labels", add_labels_options, run_labels_command)};

}  // namespace

}  // namespace keymesh::cli
