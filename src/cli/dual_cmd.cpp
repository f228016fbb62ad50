// keymesh dual IN -o OUT: one polygon per input point through the centroids
// of its cells, keyed by the point.
#include <cstdio>

#include "command.hpp"
#include "keymesh/generate/dual.hpp"
#include "keymesh/generate/report_fields.hpp"
#include "keymesh/io/mesh_io.hpp"

namespace keymesh::cli {

namespace {

struct DualCli {
  std::string input, output;
  CommonOptions common;
};

void add_dual_options(CLI::App& cmd, DualCli& o) {
  cmd.description("the dual of a polygon surface: a polygon per point through the centroids of its cells");
  cmd.add_option("input", o.input, "polygon surface (.vtp .ply .obj .stl)")->required();
  cmd.add_option("-o,--output", o.output, "output polygons (.vtp .obj .ply)")->required();
  add_common_options(cmd, o.common);
}

int run_dual(const DualCli& o, CommandRun& run) {
  if (!is_mesh_path(o.output) || o.output.size() < 4 ||
      o.output.compare(o.output.size() - 4, 4, ".stl") == 0) {
    std::fprintf(stderr, "keymesh dual: %s: write polygons as .vtp, .obj or .ply\n", o.output.c_str());
    return 2;
  }
  const SurfaceMesh m = run.stage("read", [&] { return io::read_mesh(o.input); });
  generate::DualStats st;
  const SurfaceMesh d = run.stage("dual", [&] { return generate::dual(m, &st); });
  run.stage("write", [&] { io::write_mesh(d, o.output); });
  if (!o.common.quiet) {
    std::fprintf(stderr, "keymesh: %lld points, %lld polygons -> %s\n", (long long)d.num_points(),
                 (long long)d.num_cells(), o.output.c_str());
    if (st.boundary_fans || st.nonmanifold_points || st.skipped_fans)
      std::fprintf(stderr, "keymesh: %lld boundary fans, %lld non-manifold points, %lld fans skipped\n",
                   (long long)st.boundary_fans, (long long)st.nonmanifold_points, (long long)st.skipped_fans);
  }
  nlohmann::json r = files_and_counts(o.input, o.output, d.num_points(), d.num_cells());
  r["input_points"] = m.num_points();
  r["input_cells"] = m.num_cells();
  generate::visit_fields(st, into(r));
  return run.finish(r, PeakRss::Include);
}

Register reg{make_cpu_command("dual", "the dual", add_dual_options, run_dual)};

}  // namespace

}  // namespace keymesh::cli
