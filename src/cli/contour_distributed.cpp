#include "contour_distributed.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <numeric>

#include "command.hpp"
#include "keymesh/distributed/contour_distributed.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/plane_source.hpp"
#include "keymesh/io/vtp.hpp"

namespace keymesh::cli {

namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && std::equal(tail.rbegin(), tail.rend(), s.rbegin());
}

nlohmann::json rank_json(const distributed::RankStats& s) {
  return {{"first_plane", s.first_plane},       {"planes", s.planes},
          {"points", s.points},                 {"points_owned", s.points_owned},
          {"triangles", s.triangles},           {"keys_requested", s.keys_requested},
          {"bytes_sent", s.bytes_sent},         {"read", s.read},
          {"balance", s.balance},               {"contour", s.contour},
          {"wait", s.wait},
          {"exchange", s.exchange},
          {"output", s.output}};
}

}  // namespace

int run_distributed_contour(const DistributedContourJob& job) {
  const int rank = distributed::rank(), ranks = distributed::size();
  const bool pieces = ends_with(job.output, ".pvtp");
  if (pieces && job.gather) {
    if (rank == 0)
      std::fprintf(stderr, "keymesh contour: --gather writes one file; %s is an index of pieces (use .vtp .ply ...)\n",
                   job.output.c_str());
    return 2;
  }
  StageTimer timer;
  // Checks every rank makes alike: refused with one message, no MPI_Abort.
  std::unique_ptr<PlaneSource> source;
  try {
    source = io::open_volume_planes(job.input, job.raw_given ? &job.raw : nullptr);
    distributed::require_distributable(source->header(), job.options, ranks);
  } catch (const std::exception& e) {
    if (rank == 0) std::fprintf(stderr, "keymesh: %s\n", e.what());
    return 1;
  }
  distributed::ContourPiece piece = timer.run("contour", [&] { return distributed::contour_piece(*source, job.options, job.balance); });
  SurfaceMesh whole;
  double total_points = static_cast<double>(piece.numbering.total);
  if (pieces) {
    // Every rank writes its piece; rank 0 writes the index once all exist,
    // so a failure anywhere leaves no index and no pieces.
    namespace fs = std::filesystem;
    const fs::path index(job.output);
    const std::string stem = index.stem().string();
    auto piece_name = [&](int q) { return stem + "_" + std::to_string(q) + ".vtp"; };
    const fs::path mine = index.parent_path() / piece_name(rank);
    bool ok = true;
    timer.run("write", [&] {
      const auto t0 = std::chrono::steady_clock::now();
      try {
        io::write_vtp(piece.mesh, mine.string(), &piece.numbering.ids);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "keymesh: rank %d: %s\n", rank, e.what());
        ok = false;
      }
      ok = distributed::all_ok(ok);
      if (ok && rank == 0) {
        std::vector<std::string> names;
        for (int q = 0; q < ranks; ++q) names.push_back(piece_name(q));
        try {
          io::write_pvtp(job.output, piece.mesh, names, true);
        } catch (const std::exception& e) {
          std::fprintf(stderr, "keymesh: %s\n", e.what());
          ok = false;
        }
      }
      ok = distributed::all_ok(ok);
      if (!ok) {
        std::error_code ec;
        fs::remove(mine, ec);
      }
      piece.stats.output = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    });
    if (!ok) return 1;
  } else {
    whole = timer.run("gather", [&] { return distributed::gather(piece); });
    bool ok = true;
    if (rank == 0) {
      try {
        const auto t0 = std::chrono::steady_clock::now();
        timer.run("write", [&] { io::write_mesh(whole, job.output); });
        piece.stats.output += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      } catch (const std::exception& e) {
        std::fprintf(stderr, "keymesh: %s\n", e.what());
        ok = false;
      }
    }
    if (!distributed::all_ok(ok)) return 1;
  }
  const std::vector<distributed::RankStats> all = distributed::gather_stats(piece.stats);
  if (rank != 0) return 0;

  double triangles = 0, bytes = 0, max_tris = 0;
  for (const auto& s : all) {
    triangles += s.triangles;
    bytes += s.bytes_sent;
    max_tris = std::max(max_tris, s.triangles);
  }
  if (!job.quiet)
    std::fprintf(stderr, "keymesh: %lld points, %lld triangles on %d ranks -> %s\n",
                 static_cast<long long>(total_points), static_cast<long long>(triangles), ranks, job.output.c_str());
  if (!job.report_path.empty()) {
    nlohmann::json r;
    r["input"] = job.input;
    r["output"] = job.output;
    r["dims"] = source->header().dims;
    r["scalar_type"] = scalar_type_name(source->header().type);
    r["grid"] = "voxels";
    r["isovalues"] = job.options.isovalues;
    r["weld"] = job.weld;
    r["normals"] = job.normals;
    r["points"] = static_cast<long long>(total_points);
    r["cells"] = static_cast<long long>(triangles);
    r["threads"] = job.threads;
    r["ranks"] = ranks;
    r["seconds"] = timer.seconds();
    nlohmann::json per_rank = nlohmann::json::array();
    for (const auto& s : all) per_rank.push_back(rank_json(s));
    r["distributed"] = {{"ranks", ranks},
                        {"output", pieces ? "pieces" : "gathered"},
                        {"bytes_exchanged", bytes},
                        {"triangle_imbalance", triangles > 0 ? max_tris * ranks / triangles : 1.0},
                        {"per_rank", per_rank}};
    r["peak_rss_mib"] = peak_rss_mib();
    write_report(job.report_path, r);
  }
  return 0;
}

}  // namespace keymesh::cli
