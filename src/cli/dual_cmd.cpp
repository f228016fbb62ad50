// keymesh dual IN -o OUT: one polygon per input point through the centroids
// of its cells, keyed by the point.
#include <cstdio>

#include "command.hpp"
#include "keymesh/backend/dual.hpp"
#include "keymesh/generate/unstructured/dual.hpp"
#include "keymesh/generate/report_fields.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/mesh_io.hpp"

namespace keymesh::cli {

namespace {

struct DualCli {
  std::string input, output;
  CommonOptions common;
};

void add_dual_options(Subcommand& cmd, DualCli& o) {
  cmd.description("the dual of a polygon surface: a polygon per point through the centroids of its cells");
  cmd.add_option("input", o.input, "polygon surface (" + io::extensions_of(io::DataKind::Surface, false) + ")")
      ->required();
  cmd.add_option("-o,--output", o.output,
                 "output surface (" + io::extensions_of(io::DataKind::Surface, true) + "; " +
                     io::polygon_extensions(false) + " split the polygons into fans of triangles, as convert does)")
      ->required();
  add_common_options(cmd, o.common);
}

int run_dual(const DualCli& o, CommandRun& run) {
  // A format that holds triangles only (the table's triangles_only: .stl,
  // .glb) gets each polygon as a fan, as convert and pipeline --dual write
  // them; a format that is no surface mesh is refused before the work.
  const io::Format* out = io::format_by_name(o.output);
  if (!out || out->kind != io::DataKind::Surface || !out->writable()) {
    std::fprintf(stderr, "keymesh dual: %s: write the dual as %s\n", printable(o.output).c_str(),
                 io::extensions_of(io::DataKind::Surface, true).c_str());
    return 2;
  }
  const SurfaceMesh m = run.stage("read", [&] { return io::read_mesh(o.input); });
  check_work(estimate_dual(m.num_points(), m.num_cells(), m.connectivity.size(), field_components(m.point_fields)),
             memory_budget(o.common), o.input + ": dual");
  generate::DualStats st;
  const auto backend = generate::parse_option<generate::Backend>(o.common.backend);
  const SurfaceMesh d = run.stage("dual", [&] { return backend::dual(m, backend, &st); });
  run.stage("write", [&] { io::write_mesh(d, o.output); });
  if (!o.common.quiet) {
    std::fprintf(stderr, "keymesh: %lld points, %lld polygons -> %s\n", (long long)d.num_points(),
                 (long long)d.num_cells(), printable(o.output).c_str());
    if (st.boundary_fans || st.nonmanifold_points || st.skipped_fans)
      std::fprintf(stderr, "keymesh: %lld boundary fans, %lld non-manifold points, %lld fans skipped\n",
                   (long long)st.boundary_fans, (long long)st.nonmanifold_points, (long long)st.skipped_fans);
  }
  nlohmann::json r = files_and_counts(o.input, o.output, d.num_points(), d.num_cells());
  r["input_points"] = m.num_points();
  r["input_cells"] = m.num_cells();
  generate::visit_fields(st, into(r));
  r["backend"] = o.common.backend;
  return run.finish(r, PeakRss::Include);
}

Register reg{make_run_command("dual", add_dual_options, run_dual)};

}  // namespace

}  // namespace keymesh::cli
