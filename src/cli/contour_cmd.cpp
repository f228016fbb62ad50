// keymesh contour IN -o OUT --iso V [...]: marching cubes welded by KEY-REDUCE.
// One run_* function per path (see contour_cli.hpp); run_contour picks one,
// and every single-process path ends in finish_contour (coarsening's
// topology, the write, the summary line and the report).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "contour_cli.hpp"
#include "keymesh/analyze/topology.hpp"
#include "keymesh/backend/contour.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/generate/contour/contour_stream.hpp"
#include "keymesh/generate/unstructured/contour_tets.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/grid_io.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/plane_source.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

generate::ContourOptions contour_options(const ContourCli& o) {
  generate::ContourOptions opt;
  opt.isovalues = o.isovalues;
  opt.weld = generate::parse_option<generate::ContourWeld>(o.weld);
  opt.normals = generate::parse_option<generate::ContourNormals>(o.normals);
  opt.scalars = !o.no_scalars;
  opt.array = o.array;
  opt.coarsen = o.coarsen;
  opt.max_output_bytes = memory_budget(o.common);
  opt.curvature = o.curvature;
  opt.history = o.history;
  opt.backend = generate::parse_option<generate::Backend>(o.common.backend);
  return opt;
}

nlohmann::json contour_report(const ContourCli& o, long long points, long long cells, int threads,
                              const StageTimer& timer) {
  nlohmann::json r = files_and_counts(o.input, o.output, points, cells);
  r["isovalues"] = o.isovalues;
  r["weld"] = o.weld;
  r["normals"] = o.normals;
  r["threads"] = threads;
  r["seconds"] = timer.seconds();
  return r;
}

nlohmann::json coarsening_report(const ContourCli& o, const SurfaceMesh& mesh, Id triangles_before,
                                 StageTimer& timer) {
  const auto topo = timer.run("check", [&] { return analyze::check_fans(mesh); });
  nlohmann::json r;
  r["triangles_before"] = triangles_before;
  r["triangles_after"] = mesh.num_cells();
  r["nonmanifold_edges"] = topo.nonmanifold_edges;
  r["nonmanifold_vertices"] = topo.nonmanifold_vertices;
  r["boundary_edges"] = topo.boundary_edges;
  if (!o.common.quiet && (topo.nonmanifold_edges || topo.nonmanifold_vertices))
    std::fprintf(stderr, "keymesh: coarsening left %lld non-manifold edges and %lld non-manifold vertices\n",
                 (long long)topo.nonmanifold_edges, (long long)topo.nonmanifold_vertices);
  return r;
}

int refuse_history_usage(const ContourCli& o, bool say, bool distributed) {
  if (!o.history) return 0;
  std::string why;
  if (o.coarsen)
    why = "--history with --coarsen: a coarsened point merges crossings of several edges, so it has no one edge "
          "and t";
  else if (io::file_extension(o.output) != ".vtp" && !(distributed && io::file_extension(o.output) == ".pvtp"))
    why = "--history writes history_key as UInt64, which only .vtp holds (" + o.output + ")";
  if (why.empty()) return 0;
  if (say) std::fprintf(stderr, "keymesh contour: %s (docs/HISTORY.md)\n", why.c_str());
  return 2;
}

void write_contour(const ContourCli& o, const SurfaceMesh& mesh, const std::vector<std::uint64_t>& history_key) {
  if (o.history) io::write_vtp(mesh, o.output, nullptr, nullptr, {{"history_key", &history_key}});
  else io::write_mesh(mesh, o.output);
}

namespace {

// What a single-process path made: the mesh, the contour's statistics and
// the report keys only that path knows (the grid it read, the slabs).
struct ContourResult {
  SurfaceMesh mesh;
  std::vector<std::uint64_t> history_key;  // --history: each point's edge key
  generate::ContourStats stats;
  nlohmann::json facts = nlohmann::json::object();
};

void warn_isovalues_outside(const ContourCli& o, std::array<double, 2> range) {
  for (double iso : o.isovalues)
    if ((iso < range[0] || iso > range[1]) && !o.common.quiet)
      std::fprintf(stderr, "keymesh: warning: isovalue %g is outside the data range [%g, %g]\n", iso, range[0],
                   range[1]);
}

// The finite range of a point field ({0, 0} when it has no finite value).
std::array<double, 2> finite_range(const Field& f) {
  std::array<double, 2> range{0, 0};
  bool any = false;
  for (float v : f.values)
    if (std::isfinite(v)) {
      range = any ? std::array<double, 2>{std::min<double>(range[0], v), std::max<double>(range[1], v)}
                  : std::array<double, 2>{v, v};
      any = true;
    }
  return range;
}

// --memory-limit: the volume read and contoured slab by slab.
ContourResult run_streamed(const ContourCli& o, const generate::ContourOptions& opt, StageTimer& timer) {
  std::size_t limit = 0;
  parse_size(o.memory_limit, limit);  // checked by its validator
  const io::RawOptions raw = o.raw_input.given() ? o.raw_input.options() : io::RawOptions{};
  auto source = io::open_volume_planes(o.input, o.raw_input.given() ? &raw : nullptr);
  ContourResult result;
  generate::StreamStats ss;
  result.mesh =
      timer.run("contour", [&] {
        return generate::contour_streamed(*source, opt, limit, &result.stats, &ss,
                                          opt.history ? &result.history_key : nullptr);
      });
  timer.add("read", ss.read);
  nlohmann::json& r = result.facts;
  r["dims"] = source->header().dims;
  r["scalar_type"] = scalar_type_name(source->header().type);
  r["grid"] = "voxels";
  r["memory_limit"] = limit;
  r["stream"] = {{"slabs", ss.slabs},         {"planes_per_slab", ss.planes_per_slab},
                 {"slab_bytes", ss.slab_bytes}, {"read", ss.read},
                 {"contour", ss.contour},       {"merge", ss.merge},
                 {"fine_points", ss.fine_points}, {"most_fine_points_held", ss.most_fine_points_held}};
  return result;
}

// A tetrahedral grid: marching tetrahedra over one of its point fields.
ContourResult run_tets(const ContourCli& o, const generate::ContourOptions& opt, StageTimer& timer,
                       Progress& progress) {
  const UnstructuredGrid grid = timer.run("read", [&] { return io::read_grid(o.input); });
  progress.enable_if(grid.num_cells() > (1ll << 26));
  ContourResult result;
  for (const Field& f : grid.point_fields)
    if (o.array.empty() ? f.components == 1 : f.name == o.array) {
      warn_isovalues_outside(o, finite_range(f));
      result.facts["array"] = f.name;
      break;
    }
  progress.say("contouring " + std::to_string(grid.num_cells()) + " tetrahedra");
  result.mesh = timer.run("contour", [&] {
    return backend::contour(grid, opt, &result.stats, opt.history ? &result.history_key : nullptr);
  });
  result.facts["input_points"] = grid.num_points();
  result.facts["input_cells"] = grid.num_cells();
  result.facts["grid"] = "tetrahedra";
  return result;
}

// A volume read whole: marching cubes.
ContourResult run_voxels(const ContourCli& o, const generate::ContourOptions& opt, StageTimer& timer,
                         Progress& progress) {
  const io::RawOptions raw = o.raw_input.given() ? o.raw_input.options() : io::RawOptions{};
  const ImageGrid grid =
      timer.run("read", [&] { return io::read_volume(o.input, o.raw_input.given() ? &raw : nullptr); });
  progress.enable_if(grid.num_points() > (1ll << 25));
  warn_isovalues_outside(o, scalar_range(grid));
  progress.say("contouring " + std::to_string(grid.dims[0]) + "x" + std::to_string(grid.dims[1]) + "x" +
               std::to_string(grid.dims[2]) + " " + scalar_type_name(grid.type));
  ContourResult result;
  result.mesh = timer.run("contour", [&] {
    return backend::contour(grid, opt, &result.stats, opt.history ? &result.history_key : nullptr);
  });
  nlohmann::json& r = result.facts;
  r["dims"] = grid.dims;
  r["scalar_type"] = scalar_type_name(grid.type);
  r["grid"] = "voxels";
  // What the run had to hold at least: the samples read (beside output_mib).
  double samples = 1;
  for (Id d : grid.dims) samples *= static_cast<double>(d);
  r["input_mib"] = samples * static_cast<double>(scalar_size(grid.type)) / (1 << 20);
  return result;
}

// --coarsen: what the collapse did to the topology (outside the contour's
// time), in the report and, when it left non-manifold parts, on stderr.
void report_coarsening(const ContourCli& o, ContourResult& result, StageTimer& timer) {
  result.facts.update(coarsening_report(o, result.mesh, result.stats.triangles_before_coarsening, timer));
}

// MiB of the mesh written: positions, connectivity, offsets, point fields.
double mesh_mib(const SurfaceMesh& mesh) {
  double bytes = 4.0 * static_cast<double>(mesh.points.size() + mesh.connectivity.size()) +
                 8.0 * static_cast<double>(mesh.offsets.size());
  for (const Field& f : mesh.point_fields) bytes += 4.0 * static_cast<double>(f.values.size());
  return bytes / (1 << 20);
}

int finish_contour(const ContourCli& o, const generate::ContourOptions& opt, ContourResult& result, int threads,
                   StageTimer& timer, Progress& progress) {
  const SurfaceMesh& mesh = result.mesh;
  if (o.coarsen) report_coarsening(o, result, timer);
  progress.say("writing " + o.output);
  timer.run("write", [&] { write_contour(o, mesh, result.history_key); });
  say_written(o.common, mesh.num_points(), mesh.num_cells(), "triangles", o.output);
  if (o.common.report_path.empty()) return 0;
  nlohmann::json r = contour_report(o, mesh.num_points(), mesh.num_cells(), threads, timer);
  r.update(result.facts);
  const generate::ContourStats& stats = result.stats;
  r["soup_points"] = stats.soup_points;
  r["key_bits"] = stats.key_bits;
  r["coarsen"] = o.coarsen;
  r["contour_stages"] = {{"coarsen", stats.coarsen},
                         {"classify", stats.classify},
                         {"generate", stats.generate},
                         {"weld", stats.weld},
                         {"fields", stats.fields}};
  r["peak_rss_mib"] = peak_rss_mib();
  r["output_mib"] = mesh_mib(mesh);
  if (opt.backend == generate::Backend::Cuda)
    r["device_peak_mib"] = static_cast<double>(stats.device_peak_bytes) / (1 << 20);
  write_report(o.common.report_path, r);
  return 0;
}

// Under mpirun (several ranks, or one rank given raw input to stream).
bool runs_distributed(const ContourCli& o) {
  return distributed::size() > 1 ||
         (distributed::launched_by_mpi() && o.raw_input.given() && o.memory_limit.empty());
}

// Usage errors of the distributed contour (exit 2, said once by rank 0).
// --memory-limit streams each rank's planes (its halo layers too, for
// coarsened pieces), except with --balance, which counts the equal slab's
// layers and keeps it.
int refuse_distributed_usage(const ContourCli& o) {
  const bool tets = !o.raw_input.given() && io::is_grid_file(o.input);
  std::string why;
  if (tets)
    why = o.input + ": marching tetrahedra is not distributed; run it as one process";
  else if (!o.memory_limit.empty() && o.balance)
    why = "--memory-limit with --balance under mpirun: balancing holds each rank's equal slab; drop one of them";
  if (why.empty()) return 0;
  if (distributed::rank() == 0) std::fprintf(stderr, "keymesh contour: %s\n", why.c_str());
  return 2;
}

// Options a tetrahedral grid cannot honour: they read the volume's derivatives.
int refuse_tet_options(const generate::ContourOptions& opt) {
  if (opt.normals != generate::ContourNormals::Gradient && !opt.curvature) return 0;
  std::fprintf(stderr, "keymesh contour: %s needs a voxel grid%s\n",
               opt.curvature ? "--curvature" : "--normals gradient", opt.curvature ? "" : "; use --normals average");
  return 2;
}

int run_contour(const ContourCli& o) {
  if (int rc = refuse_non_finite_isovalues("contour", o.isovalues)) return rc;
  const int threads = apply_threads(o.common);
  StageTimer timer;
  Progress progress(o.common.quiet, file_size(o.input) > (64ll << 20));
  const generate::ContourOptions opt = contour_options(o);
  if (runs_distributed(o)) {
    if (int rc = refuse_distributed_usage(o)) return rc;
    if (int rc = refuse_history_usage(o, distributed::rank() == 0, true)) return rc;
    return run_distributed_contour(o, opt, threads);
  }
  if (int rc = refuse_history_usage(o, true, false)) return rc;
  ContourResult result;
  if (!o.memory_limit.empty()) {
    result = run_streamed(o, opt, timer);
  } else if (!o.raw_input.given() && io::is_grid_file(o.input)) {
    progress.say("reading " + o.input);
    if (int rc = refuse_tet_options(opt)) return rc;
    result = run_tets(o, opt, timer, progress);
  } else {
    progress.say("reading " + o.input);
    result = run_voxels(o, opt, timer, progress);
  }
  return finish_contour(o, opt, result, threads, timer, progress);
}

void add_contour_options(Subcommand& cmd, ContourCli& o) {
  cmd.add_option("input", o.input,
                 "volume: " + io::accepted_volumes(false) + "; or a tetrahedral grid: " +
                     io::extensions_of(io::DataKind::Grid, false, ", ") + " (UNSTRUCTURED_GRID)")
      ->required();
  cmd.add_option("--array", o.array, "tet grids: the point field to contour (default: the first scalar field)");
  cmd.add_option("-o,--output", o.output,
                 "output mesh (" + io::extensions_of(io::DataKind::Surface, true) + "; under mpirun also " +
                     io::pieces_index_extensions() + ": one piece per rank)")
      ->required();
  cmd.add_option("--iso", o.isovalues, "isovalue (repeat for several)")->required()->expected(1, -1);
  cmd.add_option("--weld", o.weld,
                 "how to connect the soup: keyreduce (edge keys, structured plan: cut edges counted per row, no "
                 "soup; default), keyreduce-sort (KEY-REDUCE with the sort plan), "
                 "or vertexweld (coordinates, the paper's baseline)")
      ->check(one_of<generate::ContourWeld>());
  cmd.add_option("--normals", o.normals,
                 "point normals: none, gradient (interpolated central differences) or average "
                 "(incident face normals merged by KEY-REDUCE)")
      ->check(one_of<generate::ContourNormals>());
  cmd.add_flag("--no-scalars", o.no_scalars, "do not carry the interpolated scalar");
  cmd.add_flag("--curvature", o.curvature,
               "mean curvature per point from the volume's gradient and Hessian (point field mean_curvature; "
               "1/r on a sphere of the distance field); voxel grids only");
  cmd.add_flag("--coarsen", o.coarsen,
               "merge the points nearest to one grid point (key = nearest input point on the edge), "
               "averaging positions and fields; drop collapsed triangles; split pinched points, one per fan; "
               "remove points left without a triangle");
  cmd.add_flag("--history", o.history,
               "per point, where it came from: point arrays history_key (UInt64: its grid edge, 3 * point id + "
               "axis + isovalue index * 3N) and history_t (Float32: t along the edge from its lower end, which "
               "gives the point's position back; tet grids: the edge's two point ids; docs/HISTORY.md); .vtp "
               "output, not with --coarsen");
  o.raw_input.add_options(cmd);
  cmd.add_option("--memory-limit", o.memory_limit,
                 "stream the volume in slabs of z-planes holding at most SIZE bytes of samples (e.g. 256M, 2G; "
                 "under mpirun per rank, over its own planes); the output is byte-identical (averaged normals: "
                 "within float rounding); " +
                     io::accepted_plane_sources())
      ->check(size_validator());
  cmd.add_flag("--gather", o.gather,
               "under mpirun: gather the whole mesh on rank 0 into one file (the default unless OUT is .pvtp, "
               "which writes one OUT_<rank>.vtp piece per rank with GlobalPointIds)");
  cmd.add_flag("--balance", o.balance,
               "under mpirun: move the slab boundaries so that every rank gets about the same number of "
               "triangles (counted on the equal split first); the output is the same");
  add_common_options(cmd, o.common);
}

Register reg{make_command<ContourCli>(
    "contour", "isosurface of a volume (marching cubes) or a tet grid (marching tetrahedra), welded by edge keys",
    add_contour_options, run_contour)};

}  // namespace

}  // namespace keymesh::cli
