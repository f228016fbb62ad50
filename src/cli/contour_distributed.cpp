// `mpirun -np P keymesh contour VOLUME -o OUT`: the distributed contour's
// command-line side: each rank reads its slab, the mesh is written as one
// piece per rank (.pvtp) or gathered on rank 0, rank 0 reports.
#include <algorithm>
#include <cstdio>
#include <memory>

#include "contour_cli.hpp"
#include "piece_files.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/distributed/contour_distributed.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/plane_source.hpp"

namespace keymesh::cli {

namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && std::equal(tail.rbegin(), tail.rend(), s.rbegin());
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

nlohmann::json rank_json(const distributed::RankStats& s) {
  return {{"first_plane", s.first_plane},       {"planes", s.planes},
          {"slabs", s.slabs},
          {"points", s.points},                 {"points_owned", s.points_owned},
          {"fine_points_held", s.fine_points_held},
          {"triangles", s.triangles},           {"keys_requested", s.keys_requested},
          {"bytes_sent", s.bytes_sent},         {"read", s.read},
          {"balance", s.balance},               {"contour", s.contour},
          {"wait", s.wait},
          {"exchange", s.exchange},
          {"output", s.output}};
}

// This rank's planes, once every rank has opened the volume and made the
// checks all make alike: an error on any rank is every rank's (SharedError,
// said once by rank 0), with no MPI_Abort.
std::unique_ptr<PlaneSource> open_slab_source(const ContourCli& o, const generate::ContourOptions& options) {
  std::unique_ptr<PlaneSource> source;
  distributed::agreed([&] {
    const io::RawOptions raw = o.raw_input.given() ? o.raw_input.options() : io::RawOptions{};
    source = io::open_volume_planes(o.input, o.raw_input.given() ? &raw : nullptr);
    distributed::require_distributable(source->header(), options, distributed::size());
  });
  return source;
}

// Every rank writes its piece (its triangles, then the ghost cells it
// carries for its neighbours); rank 0 writes the index once all exist, so a
// failure anywhere leaves no index and no pieces.
void write_pieces(distributed::ContourPiece& piece, const std::string& output, bool history) {
  const auto t0 = std::chrono::steady_clock::now();
  // With one layer of ghost cells from the neighbouring slabs, marked as VTK
  // marks them: per-piece filters see across the shared planes (issue 33).
  distributed::GhostedPiece ghosted = distributed::ghosted_piece(piece);
  const io::PieceGhosts ghosts{std::move(ghosted.point_ghosts), std::move(ghosted.cell_ghosts)};
  std::vector<io::UInt64PointArray> wide;
  if (history) wide.push_back({"history_key", &ghosted.keys});
  write_piece_files(ghosted.mesh, ghosted.ids, ghosts, output, wide);
  piece.stats.output = seconds_since(t0);
}

// The whole mesh gathered on rank 0, which writes it; its failure is every
// rank's (SharedError). Rank 0 then holds the whole fine mesh.
void write_gathered(const ContourCli& o, distributed::ContourPiece& piece, StageTimer& timer) {
  std::vector<std::uint64_t> history_key;
  const SurfaceMesh whole =
      timer.run("gather", [&] { return distributed::gather(piece, o.history ? &history_key : nullptr); });
  distributed::agreed([&] {
    if (distributed::rank() != 0) return;
    piece.stats.fine_points_held = std::max(piece.stats.fine_points_held, static_cast<double>(whole.num_points()));
    const auto t0 = std::chrono::steady_clock::now();
    timer.run("write", [&] { write_contour(o, whole, history_key); });
    piece.stats.output += seconds_since(t0);
  });
}

// Rank 0's summary line and report, from every rank's statistics.
void report_distributed(const ContourCli& o, const PlaneSource& source, double total_points,
                        const std::vector<distributed::RankStats>& all, int threads, const StageTimer& timer) {
  const int ranks = distributed::size();
  double triangles = 0, bytes = 0, max_tris = 0;
  for (const auto& s : all) {
    triangles += s.triangles;
    bytes += s.bytes_sent;
    max_tris = std::max(max_tris, s.triangles);
  }
  if (!o.common.quiet)
    std::fprintf(stderr, "keymesh: %lld points, %lld triangles on %d ranks -> %s\n",
                 static_cast<long long>(total_points), static_cast<long long>(triangles), ranks, o.output.c_str());
  if (o.common.report_path.empty()) return;
  nlohmann::json r = contour_report(o, static_cast<long long>(total_points), static_cast<long long>(triangles),
                                    threads, timer);
  r["dims"] = source.header().dims;
  r["scalar_type"] = scalar_type_name(source.header().type);
  r["grid"] = "voxels";
  r["ranks"] = ranks;
  nlohmann::json per_rank = nlohmann::json::array();
  for (const auto& s : all) per_rank.push_back(rank_json(s));
  r["distributed"] = {{"ranks", ranks},
                      {"output", ends_with(o.output, ".pvtp") ? "pieces" : "gathered"},
                      {"bytes_exchanged", bytes},
                      {"triangle_imbalance", triangles > 0 ? max_tris * ranks / triangles : 1.0},
                      {"per_rank", per_rank}};
  r["peak_rss_mib"] = peak_rss_mib();
  write_report(o.common.report_path, r);
}

// --memory-limit: bytes of samples a rank holds at once (0: its whole slab).
std::size_t memory_limit(const ContourCli& o) {
  std::size_t limit = 0;
  if (!o.memory_limit.empty()) parse_size(o.memory_limit, limit);  // checked by its validator
  return limit;
}

}  // namespace

int run_distributed_contour(const ContourCli& o, const generate::ContourOptions& options, int threads) {
  const bool pieces = ends_with(o.output, ".pvtp");
  if (pieces && o.gather) {
    if (distributed::rank() == 0)
      std::fprintf(stderr, "keymesh contour: --gather writes one file; %s is an index of pieces (use .vtp .ply ...)\n",
                   o.output.c_str());
    return 2;
  }
  StageTimer timer;
  const std::unique_ptr<PlaneSource> source = open_slab_source(o, options);
  if (o.coarsen) return run_coarse_pieces(o, options, *source, threads, memory_limit(o));
  distributed::ContourPiece piece =
      timer.run("contour", [&] { return distributed::contour_piece(*source, options, o.balance, memory_limit(o)); });
  const double total_points = static_cast<double>(piece.numbering.total);
  if (pieces)
    timer.run("write", [&] { write_pieces(piece, o.output, o.history); });
  else
    write_gathered(o, piece, timer);
  const std::vector<distributed::RankStats> all = distributed::gather_stats(piece.stats);
  if (distributed::rank() != 0) return 0;
  report_distributed(o, *source, total_points, all, threads, timer);
  return 0;
}

}  // namespace keymesh::cli
