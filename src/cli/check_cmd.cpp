// keymesh check MESH [--expect-closed] [--self-intersections]: is the mesh a
// closed 2-manifold, and (on request) does it cross itself anywhere?
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
  bool self_intersections = false;
  CommonOptions common;
};

void add_check_options(Subcommand& cmd, CheckCli& o) {
  cmd.description("topology of a surface mesh: boundary and non-manifold edges, duplicates, Euler characteristic");
  cmd.add_option("mesh", o.input, "surface mesh (" + io::extensions_of(io::DataKind::Surface, false) + ")")->required();
  cmd.add_flag("--expect-closed", o.expect_closed,
               "exit 1 unless the mesh is a closed 2-manifold (and, with --self-intersections, crosses itself nowhere)");
  cmd.add_flag("--self-intersections", o.self_intersections,
               "also look for pairs of cells that cross or touch where they share no corner (exact predicates); "
               "report keys self_intersections, self_intersecting_pairs, zero_area_triangles");
  add_common_options(cmd, o.common);
}

int run_check(const CheckCli& o, CommandRun& run) {
  const SurfaceMesh mesh = run.stage("read", [&] { return io::read_mesh(o.input); });
  // The mesh, and the check's edge table: a (key, value) pair of 16 bytes per corner.
  check_memory(o.common, saturating_add(bytes_held(mesh), saturating_mul(mesh.connectivity.size(), 16)),
               o.input + ": check: the mesh and its edges");
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
  Id crossing = 0;
  if (o.self_intersections) {
    const analyze::SelfIntersectionReport s =
        run.stage("self_intersections", [&] { return analyze::find_self_intersections(mesh); });
    std::printf("  self-intersections %lld (pairs of cells), zero-area triangles %lld\n", (long long)s.self_intersections,
                (long long)s.zero_area_triangles);
    for (const auto& pair : s.pairs) std::printf("    cells %lld and %lld cross\n", (long long)pair[0], (long long)pair[1]);
    if (s.self_intersections > static_cast<Id>(s.pairs.size()))
      std::printf("    ... and %lld more pairs\n", (long long)(s.self_intersections - static_cast<Id>(s.pairs.size())));
    analyze::visit_fields(s, into(r));
    crossing = s.self_intersections;
  }
  run.finish(r, PeakRss::Omit);
  if (!o.expect_closed || (t.closed_manifold && crossing == 0)) return 0;
  // The check itself ran: its report is written though the exit is 1.
  if (io::OutputTransaction* outputs = io::OutputTransaction::current()) outputs->commit();
  if (!t.closed_manifold) std::fprintf(stderr, "keymesh: %s is not a closed 2-manifold\n", printable(o.input).c_str());
  if (crossing != 0)
    std::fprintf(stderr, "keymesh: %s crosses itself (%lld pairs of cells)\n", printable(o.input).c_str(), (long long)crossing);
  return 1;
}

Register reg{make_cpu_command("check", "the topology check", add_check_options, run_check)};

}  // namespace

}  // namespace keymesh::cli
