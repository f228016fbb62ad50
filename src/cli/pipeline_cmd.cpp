// keymesh pipeline IN -o OUT --iso V [--coarsen] [--subdivide K] [--dual]
// [--curvature]: the paper's Figure 8 chain in memory, every stage keyed.
#include <cstdio>

#include "command.hpp"
#include "keymesh/backend/contour.hpp"
#include "keymesh/backend/dual.hpp"
#include "keymesh/backend/subdivide.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/unstructured/contour_tets.hpp"
#include "keymesh/generate/unstructured/dual.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/grid_io.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

namespace {

struct PipelineCli {
  std::string input, output;
  std::vector<double> isovalues;
  bool coarsen = false, curvature = false, dual = false;
  bool history = false;  // the contour's history_key and history_t (the contour stage alone)
  int subdivide = 0;
  std::string scheme = "linear";
  std::string normals = "average";
  CommonOptions common;
};

// Contour, then the optional stages in the paper's order, all in memory.
SurfaceMesh run_stages(const PipelineCli& o, StageTimer& timer, nlohmann::json& r,
                       std::vector<std::uint64_t>& history_key) {
  generate::ContourOptions opt;
  opt.history = o.history;
  std::vector<std::uint64_t>* keys = o.history ? &history_key : nullptr;
  opt.isovalues = o.isovalues;
  opt.coarsen = o.coarsen;
  opt.curvature = o.curvature;
  opt.backend = generate::parse_option<generate::Backend>(o.common.backend);
  opt.normals = generate::parse_option<generate::ContourNormals>(o.normals);
  opt.max_output_bytes = memory_budget(o.common);  // the contour checks its output's size as it counts it
  SurfaceMesh mesh;
  if (io::is_grid_file(o.input)) {
    const UnstructuredGrid g = timer.run("read", [&] { return io::read_grid(o.input); });
    mesh = timer.run("contour", [&] { return backend::contour(g, opt, nullptr, keys); });
  } else {
    const ImageGrid g = timer.run("read", [&] { return io::read_volume(o.input); });
    mesh = timer.run("contour", [&] { return backend::contour(g, opt, nullptr, keys); });
  }
  r["contour_cells"] = mesh.num_cells();
  if (o.subdivide > 0) {
    generate::SubdivideOptions so;
    so.levels = o.subdivide;
    so.scheme = generate::parse_option<generate::SubdivideScheme>(o.scheme);
    check_work(estimate_subdivide_triangles(mesh.num_points(), mesh.num_cells(), o.subdivide,
                                            field_components(mesh.point_fields)),
               memory_budget(o.common), o.input + ": pipeline --subdivide " + std::to_string(o.subdivide));
    mesh = timer.run("subdivide", [&] { return backend::subdivide(mesh, so, opt.backend); });
  }
  if (o.dual)
    check_work(estimate_dual(mesh.num_points(), mesh.num_cells(), mesh.connectivity.size(),
                             field_components(mesh.point_fields)),
               memory_budget(o.common), o.input + ": pipeline --dual");
  if (o.dual) mesh = timer.run("dual", [&] { return backend::dual(mesh, opt.backend); });
  return mesh;
}

// --history: the contour's arrays, which name one input element per point
// only when no later stage makes points of several (docs/HISTORY.md).
int refuse_history_usage(const PipelineCli& o) {
  if (!o.history) return 0;
  std::string why;
  if (o.coarsen)
    why = "--history with --coarsen: a coarsened point merges crossings of several edges, so it has no one edge";
  else if (o.subdivide > 0)
    why = "--history with --subdivide: a subdivision point lies between two or more contour points, so it has no "
          "one input edge";
  else if (o.dual)
    why = "--history with --dual: a dual point is a face's centre, made of several contour points";
  else if (io::file_extension(o.output) != ".vtp")
    why = "--history writes history_key as UInt64, which only .vtp holds (" + o.output + ")";
  if (why.empty()) return 0;
  std::fprintf(stderr, "keymesh pipeline: %s (docs/HISTORY.md)\n", printable(why).c_str());
  return 2;
}

int run_pipeline(const PipelineCli& o) {
  if (int rc = refuse_non_finite_isovalues("pipeline", o.isovalues)) return rc;
  if (int rc = refuse_history_usage(o)) return rc;
  if (o.scheme == "bezier" && o.normals == "none") {
    std::fprintf(stderr, "keymesh pipeline: --scheme bezier needs --normals average or gradient\n");
    return 2;
  }
  const int threads = apply_threads(o.common);
  StageTimer timer;
  nlohmann::json r;
  std::vector<std::uint64_t> history_key;
  const SurfaceMesh mesh = run_stages(o, timer, r, history_key);
  timer.run("write", [&] {
    if (o.history) io::write_vtp(mesh, o.output, nullptr, nullptr, {{"history_key", &history_key}});
    else io::write_mesh(mesh, o.output);
  });
  say_written(o.common, mesh.num_points(), mesh.num_cells(), "cells", o.output);
  r.update(files_and_counts(o.input, o.output, mesh.num_points(), mesh.num_cells()));
  finish_report(o.common, r, threads, timer, PeakRss::Include);
  return 0;
}

void add_pipeline_options(Subcommand& cmd, PipelineCli& o) {
  cmd.add_option("input", o.input,
                 "volume (" + volume_inputs() + ") or tet grid (" +
                     io::extensions_of(io::DataKind::Grid, false) + ")")
      ->required();
  cmd.add_option("-o,--output", o.output,
                 "output surface (" + io::extensions_of(io::DataKind::Surface, true) + "; with --dual " +
                     io::polygon_extensions(false) + " split the polygons into triangles)")
      ->required();
  cmd.add_option("--iso", o.isovalues, "isovalue (repeat for several)")->required()->expected(1, -1);
  cmd.add_flag("--coarsen", o.coarsen, "merge points by nearest grid point during the contour");
  cmd.add_flag("--curvature", o.curvature, "mean curvature from the volume (voxel grids), carried along");
  cmd.add_option("--subdivide", o.subdivide, "levels of 1->4 subdivision")->check(in_range(0, 6));
  cmd.add_option("--scheme", o.scheme, "subdivision positions: linear or bezier")
      ->check(one_of<generate::SubdivideScheme>());
  cmd.add_option("--normals", o.normals, "none, gradient or average (bezier needs normals)")
      ->check(one_of<generate::ContourNormals>());
  cmd.add_flag("--dual", o.dual, "finish with the dual mesh");
  cmd.add_flag("--history", o.history,
               "per point, the contour's history_key (UInt64) and history_t (Float32), as keymesh contour --history "
               "writes them (docs/HISTORY.md): the contour stage alone (not with --coarsen, --subdivide or --dual, "
               "whose points merge or interpolate several), .vtp output");
  add_common_options(cmd, o.common);
}

Register reg{make_command<PipelineCli>(
    "pipeline", "contour, then optionally coarsen, subdivide and take the dual, in memory (the paper's Figure 8)",
    add_pipeline_options, run_pipeline)};

}  // namespace

}  // namespace keymesh::cli
