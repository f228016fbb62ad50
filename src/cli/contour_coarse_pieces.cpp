// `mpirun -np P keymesh contour VOLUME --coarsen -o OUT`: every rank
// coarsens its own layers with a halo (issue 36; distributed/coarse_pieces.hpp:
// halo layers, the split's rounds agreed, the halo grown while a decision
// reaches past it). Into OUT.pvtp every rank writes its own piece, nothing
// is gathered; into any other file only the coarse pieces are gathered
// (distributed/gather_pieces.hpp) and rank 0 writes the one process's file.
// Rank 0 writes the index and the report from every rank's entry.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "contour_cli.hpp"
#include "piece_files.hpp"
#include "rank_entries.hpp"
#include "keymesh/distributed/coarse_pieces.hpp"
#include "keymesh/distributed/contour_distributed.hpp"
#include "keymesh/distributed/gather_pieces.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/plane_source.hpp"

namespace keymesh::cli {

namespace {

// This rank's entry of the report.
nlohmann::json rank_entry(const distributed::CoarsePiece& c, const StageTimer& timer) {
  const distributed::OwnPiece& w = c.piece;
  return {{"first_layer", c.first_layer}, {"layers", c.layers},
                            {"halo_layers", c.halo_layers}, {"attempts", c.attempts}, {"slabs", c.slabs},
                            {"fine_points_held", c.fine_points_held},
                            {"points", w.mesh.num_points()}, {"points_owned", w.points_owned},
                            {"triangles", w.own_triangles},
                            {"ghost_triangles", w.mesh.num_cells() - w.own_triangles},
                            {"triangles_before", c.triangles_before},
                            {"nonmanifold_edges", c.nonmanifold_edges},
                            {"nonmanifold_vertices", c.nonmanifold_vertices},
                            {"boundary_edges", c.boundary_edges},
                            {"keys_requested", w.keys_requested}, {"bytes_sent", w.bytes_sent},
                            {"read", c.read}, {"contour", c.contour}, {"coarsen", c.coarsen},
                            {"number", c.number}, {"seconds", timer.seconds()}, {"peak_rss_mib", peak_rss_mib()}};
}

// Rank 0: the summary line and the report, the counts summed from every
// rank's share (each counts its own triangles and the points, edges and
// vertices it owns).
void report_coarse_pieces(const ContourCli& o, const ImageGrid& header, long long points,
                          const nlohmann::json& per_rank, int threads, const StageTimer& timer) {
  long long triangles = 0, before = 0, edges = 0, vertices = 0, boundary = 0, halo = 0, attempts = 0;
  double bytes = 0;
  for (const nlohmann::json& q : per_rank) {
    triangles += q["triangles"].get<long long>();
    before += q["triangles_before"].get<long long>();
    edges += q["nonmanifold_edges"].get<long long>();
    vertices += q["nonmanifold_vertices"].get<long long>();
    boundary += q["boundary_edges"].get<long long>();
    halo = std::max(halo, q["halo_layers"].get<long long>());
    attempts = std::max(attempts, q["attempts"].get<long long>());
    bytes += q["bytes_sent"].get<double>();
  }
  const int ranks = static_cast<int>(per_rank.size());
  const bool pieces = o.output.ends_with(".pvtp");
  if (!o.common.quiet) {
    std::fprintf(stderr, "keymesh: %lld points, %lld triangles %s %d %s -> %s\n", points, triangles,
                 pieces ? "in" : "on", ranks, pieces ? "pieces" : "ranks", o.output.c_str());
    if (edges || vertices)
      std::fprintf(stderr, "keymesh: coarsening left %lld non-manifold edges and %lld non-manifold vertices\n", edges,
                   vertices);
  }
  if (o.common.report_path.empty()) return;
  nlohmann::json r = contour_report(o, points, triangles, threads, timer);
  r["dims"] = header.dims;
  r["scalar_type"] = scalar_type_name(header.type);
  r["grid"] = "voxels";
  r["ranks"] = ranks;
  r["coarsen"] = true;
  r["triangles_before"] = before;
  r["triangles_after"] = triangles;
  r["nonmanifold_edges"] = edges;
  r["nonmanifold_vertices"] = vertices;
  r["boundary_edges"] = boundary;
  r["distributed"] = {{"ranks", ranks}, {"output", pieces ? "pieces" : "gathered"}, {"halo_layers", halo},
                      {"attempts", attempts},
                      {"bytes_exchanged", bytes}, {"per_rank", per_rank}};
  r["peak_rss_mib"] = peak_rss_mib();
  write_report(o.common.report_path, r);
}

}  // namespace

int run_coarse_pieces(const ContourCli& o, const generate::ContourOptions& options, PlaneSource& source,
                      int threads, std::size_t memory_limit) {
  StageTimer timer;
  distributed::CoarsePiece c =
      timer.run("contour", [&] { return distributed::coarse_piece(source, options, o.balance, memory_limit); });
  if (o.output.ends_with(".pvtp")) {
    timer.run("write", [&] {
      distributed::OwnPiece& w = c.piece;
      write_piece_files(w.mesh, w.ids, io::PieceGhosts{std::move(w.point_ghosts), std::move(w.cell_ghosts)},
                        o.output);
    });
  } else {
    // Only the coarse pieces travel; rank 0's failure is every rank's (SharedError).
    distributed::agreed([&] {
      const SurfaceMesh whole = timer.run("gather", [&] {
        return distributed::gather_pieces(c.piece, c.own_isovalue, static_cast<std::uint32_t>(o.isovalues.size()));
      });
      if (distributed::rank() == 0) timer.run("write", [&] { write_contour(o, whole, {}); });
    });
  }
  const nlohmann::json per_rank = gather_rank_entries(rank_entry(c, timer));
  if (distributed::rank() == 0) report_coarse_pieces(o, source.header(), c.piece.total_points, per_rank, threads, timer);
  return 0;
}

}  // namespace keymesh::cli
