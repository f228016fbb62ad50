// keymesh check MESH [--expect-closed]: is the mesh a closed 2-manifold?
#include <cstdio>

#include "command.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/output_transaction.hpp"
#include "keymesh/analyze/report_fields.hpp"
#include "keymesh/io/mesh_io.hpp"

namespace keymesh::cli {

namespace {

struct CheckCli {
  std::string input;
  bool expect_closed = false;
  CommonOptions common;
};

void add_check_options(CLI::App& cmd, CheckCli& o) {
  cmd.description("topology of a surface mesh: boundary and non-manifold edges, duplicates, Euler characteristic");
  cmd.add_option("mesh", o.input, "surface mesh (" + io::extensions_of(io::DataKind::Surface, false) + ")")->required();
  cmd.add_flag("--expect-closed", o.expect_closed, "exit 1 unless the mesh is a closed 2-manifold");
  add_common_options(cmd, o.common);
}

int run_check(const CheckCli& o, CommandRun& run) {
  const SurfaceMesh mesh = run.stage("read", [&] { return io::read_mesh(o.input); });
  const analyze::TopologyReport t = run.stage("check", [&] { return analyze::check_topology(mesh); });
  std::printf(
      "%s: %lld points, %lld cells, %lld edges\n"
      "  boundary edges %lld, non-manifold edges %lld, non-manifold vertices %lld\n"
      "  duplicate points %lld, unused points %lld, degenerate cells %lld\n"
      "  components %lld, Euler characteristic %lld, closed 2-manifold: %s\n",
      o.input.c_str(), (long long)t.points, (long long)t.cells, (long long)t.edges, (long long)t.boundary_edges,
      (long long)t.nonmanifold_edges, (long long)t.nonmanifold_vertices, (long long)t.duplicate_points,
      (long long)t.unused_points, (long long)t.degenerate_cells, (long long)t.components,
      (long long)t.euler_characteristic, t.closed_manifold ? "yes" : "no");
  nlohmann::json r = {{"input", o.input}};
  analyze::visit_fields(t, into(r));
  run.finish(r, PeakRss::Omit);
  if (!o.expect_closed || t.closed_manifold) return 0;
  // The check itself ran: its report is written though the exit is 1.
  if (io::OutputTransaction* outputs = io::OutputTransaction::current()) outputs->commit();
  std::fprintf(stderr, "keymesh: %s is not a closed 2-manifold\n", o.input.c_str());
  return 1;
}

Register reg{make_cpu_command("check", "the topology check", add_check_options, run_check)};

}  // namespace

}  // namespace keymesh::cli
