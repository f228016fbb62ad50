// keymesh subdivide IN -o OUT [--levels K] [--scheme linear|bezier]: uniform
// subdivision of a triangle surface (1 -> 4) or a tet grid (1 -> 8), new
// points keyed by the parent edge.
#include <cstdio>

#include "command.hpp"
#include "keymesh/backend/subdivide.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/grid_io.hpp"
#include "keymesh/io/mesh_io.hpp"

namespace keymesh::cli {

namespace {

// Point ids are 32-bit (PointIndex) in the subdivided output.
constexpr std::uint64_t kMaxPoints = 0xFFFFFFFFull;

struct SubdivideCli {
  std::string input, output;
  int levels = 1;
  std::string scheme = "linear";
  std::string weld = "keyreduce";
  CommonOptions common;
};

void add_subdivide_options(Subcommand& cmd, SubdivideCli& o) {
  cmd.description("split triangles 1->4 or tetrahedra 1->8, new points keyed by the parent edge");
  cmd.add_option("input", o.input,
                 "triangle surface (" + io::extensions_of(io::DataKind::Surface, false) + ") or tet grid (" +
                     io::extensions_of(io::DataKind::Grid, false) + ")")
      ->required();
  cmd.add_option("-o,--output", o.output, "output of the same kind")->required();
  cmd.add_option("--levels,-k", o.levels, "subdivision levels")->check(in_range(0, 8));
  cmd.add_option("--scheme", o.scheme,
                 "linear (edge midpoints) or bezier (PN triangles from the point normals; surfaces only)")
      ->check(one_of<generate::SubdivideScheme>());
  cmd.add_option("--weld", o.weld, "keyreduce (edge keys) or vertexweld (coordinates, the baseline)")
      ->check(one_of<generate::SubdivideWeld>());
  add_common_options(cmd, o.common);
}

int run_subdivide(const SubdivideCli& o, CommandRun& run) {
  Progress progress(o.common.quiet, file_size(o.input) > (64ll << 20));
  generate::SubdivideOptions opt;
  opt.levels = o.levels;
  opt.scheme = generate::parse_option<generate::SubdivideScheme>(o.scheme);
  opt.weld = generate::parse_option<generate::SubdivideWeld>(o.weld);
  const auto backend = generate::parse_option<generate::Backend>(o.common.backend);
  const bool grid_in = io::is_grid_file(o.input);
  if (grid_in ? is_mesh_path(o.output) : !is_mesh_path(o.output)) {
    std::fprintf(stderr, "keymesh subdivide: %s: a %s subdivides into a %s\n", printable(o.output).c_str(),
                 grid_in ? "tet grid" : "surface",
                 (grid_in ? "grid (" + io::extensions_of(io::DataKind::Grid, true) + ")"
                          : "surface (" + io::extensions_of(io::DataKind::Surface, true) + ")")
                     .c_str());
    return 2;
  }
  if (grid_in && opt.scheme == generate::SubdivideScheme::Bezier) {
    std::fprintf(stderr, "keymesh subdivide: --scheme bezier is for surfaces; tets use linear\n");
    return 2;
  }
  progress.say("reading " + o.input);
  Id points = 0, cells = 0, in_points = 0, in_cells = 0;
  if (grid_in) {
    const UnstructuredGrid g = run.stage("read", [&] { return io::read_grid(o.input); });
    check_work(estimate_subdivide_tets(g.num_points(), g.num_cells(), o.levels, field_components(g.point_fields)),
               memory_budget(o.common), o.input + ": subdivide --levels " + std::to_string(o.levels),
               kMaxPoints);
    const UnstructuredGrid s = run.stage("subdivide", [&] { return backend::subdivide(g, opt, backend); });
    run.stage("write", [&] { io::write_grid(s, o.output); });
    in_points = g.num_points(), in_cells = g.num_cells(), points = s.num_points(), cells = s.num_cells();
  } else {
    const SurfaceMesh m = run.stage("read", [&] { return io::read_mesh(o.input); });
    check_work(estimate_subdivide_triangles(m.num_points(), m.num_cells(), o.levels,
                                            field_components(m.point_fields)),
               memory_budget(o.common), o.input + ": subdivide --levels " + std::to_string(o.levels),
               kMaxPoints, kMaxPoints / 3);
    const SurfaceMesh s = run.stage("subdivide", [&] { return backend::subdivide(m, opt, backend); });
    run.stage("write", [&] { io::write_mesh(s, o.output); });
    in_points = m.num_points(), in_cells = m.num_cells(), points = s.num_points(), cells = s.num_cells();
  }
  say_written(o.common, points, cells, "cells", o.output);
  nlohmann::json r = files_and_counts(o.input, o.output, points, cells);
  r["levels"] = o.levels;
  r["scheme"] = o.scheme;
  r["weld"] = o.weld;
  r["backend"] = o.common.backend;
  r["input_points"] = in_points;
  r["input_cells"] = in_cells;
  return run.finish(r, PeakRss::Include);
}

Register reg{make_run_command("subdivide", add_subdivide_options, run_subdivide)};

}  // namespace

}  // namespace keymesh::cli
