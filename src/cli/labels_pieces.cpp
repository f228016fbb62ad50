// `mpirun -np P keymesh labels VOLUME -o OUT.pvtp`: every rank writes its own
// piece, nothing is gathered (issue 36). Each rank makes the surfaces of its
// rows plus halo rows either side (LabelSlabs::generate_with_halo), merges,
// smooths and coarsens them as one process does, and keeps its share
// (distributed/halo_piece.hpp: its triangles, ghost cells, its points
// numbered by the distributed KEY-REDUCE). Rank 0 writes the index and the
// report from every rank's entry.
#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "labels_job.hpp"
#include "piece_files.hpp"
#include "rank_entries.hpp"
#include "keymesh/distributed/halo_piece.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/generate/labels/labels_stream.hpp"

namespace keymesh::cli {

namespace {

// This rank's share of the report's label pairs, [first, second, points,
// faces] each: its own triangles of the pair, and the points it owns that a
// triangle of the pair uses (its halo holds every triangle at such a point).
// Every point has one owner, so the ranks' shares add up to the one
// process's counts (generate::label_pair_counts).
nlohmann::json pair_shares(const generate::LabelPiece& piece, std::pair<Id, Id> rows) {
  const Field* f = piece.mesh.find_cell_field("boundary_labels");
  std::map<std::pair<long long, long long>, std::pair<std::vector<PointIndex>, long long>> pairs;
  const SurfaceMesh& m = piece.mesh;
  for (Id c = 0; f && c < m.num_cells(); ++c) {
    auto& [points, faces] = pairs[{static_cast<long long>(f->values[2 * c]), static_cast<long long>(f->values[2 * c + 1])}];
    faces += piece.ghost_face[static_cast<std::size_t>(c)] ? 0 : 1;
    for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k) {
      const PointIndex p = m.connectivity[k];
      if (rows.first <= piece.row[p] && piece.row[p] < rows.second) points.push_back(p);
    }
  }
  nlohmann::json out = nlohmann::json::array();
  for (auto& [labels, share] : pairs) {
    std::sort(share.first.begin(), share.first.end());
    const auto points = std::unique(share.first.begin(), share.first.end()) - share.first.begin();
    if (points || share.second) out.push_back({labels.first, labels.second, points, share.second});
  }
  return out;
}

// The report's pairs: every rank's shares summed, in increasing pair order.
nlohmann::json summed_pairs(const nlohmann::json& per_rank) {
  std::map<std::pair<long long, long long>, std::pair<long long, long long>> sum;
  for (const auto& e : per_rank)
    for (const auto& p : e["pairs"]) {
      auto& [points, faces] = sum[{p[0].get<long long>(), p[1].get<long long>()}];
      points += p[2].get<long long>();
      faces += p[3].get<long long>();
    }
  nlohmann::json pairs = nlohmann::json::array();
  for (const auto& [labels, n] : sum)
    pairs.push_back({{"labels", {labels.first, labels.second}}, {"points", n.first}, {"faces", n.second}});
  return pairs;
}

// Rank 0: the summary line and the report, from every rank's own entry.
void report_pieces(const LabelsJob& job, const ImageGrid& header, const generate::LabelStats& stats,
                   long long points, nlohmann::json per_rank, Id halo, StageTimer& timer) {
  long long triangles = 0;
  double bytes = 0;
  for (const auto& e : per_rank) {
    triangles += e["triangles"].get<long long>();
    bytes += e["bytes_sent"].get<double>();
  }
  const int ranks = static_cast<int>(per_rank.size());
  if (!job.common.quiet)
    std::fprintf(stderr, "keymesh: %lld labels, %lld points, %lld triangles in %d pieces -> %s\n",
                 static_cast<long long>(stats.surfaces), points, triangles, ranks, printable(job.output).c_str());
  if (job.common.report_path.empty()) return;
  const generate::LabelOptions& opt = job.options;
  nlohmann::json r = {{"input", job.input}, {"output", job.output}, {"method", job.method},
                      {"per_label", opt.per_label}, {"background", opt.background},
                      {"smooth", opt.smooth_iterations}, {"relaxation", opt.relaxation}, {"coarsen", opt.coarsen},
                      {"distinct_labels", stats.distinct_labels}, {"labels_extracted", stats.surfaces},
                      {"points", points}, {"cells", triangles}, {"threads", job.threads},
                      {"dims", header.dims}, {"scalar_type", scalar_type_name(header.type)}, {"ranks", ranks}};
  if (job.memory_limit) r["memory_limit"] = job.memory_limit;
  if (opt.coarsen) r["triangles_after"] = triangles;
  r["pairs"] = summed_pairs(per_rank);
  for (auto& e : per_rank) e.erase("pairs");
  r["distributed"] = {{"ranks", ranks}, {"output", "pieces"}, {"halo_rows", halo},
                      {"bytes_exchanged", bytes}, {"per_rank", per_rank}};
  r["seconds"] = timer.seconds();
  r["peak_rss_mib"] = peak_rss_mib();
  write_report(job.common.report_path, r);
}

// This rank's entry of the report. guard_shortened is the rank's own count,
// its halo rows' moves included: the report has no total, since the ranks'
// halos overlap (the one process's count is at most their sum).
nlohmann::json rank_entry(std::pair<Id, Id> rows, const generate::LabelSlabs& slabs, const distributed::OwnPiece& w,
                          nlohmann::json pairs, const StageTimer& timer) {
  return {{"pairs", std::move(pairs)}, {"first_row", rows.first}, {"rows", rows.second - rows.first},
          {"halo_rows", slabs.stream_stats().halo_rows}, {"slabs", slabs.stream_stats().slabs},
          {"points", w.mesh.num_points()}, {"points_owned", w.points_owned},
          {"triangles", w.own_triangles},
          {"ghost_triangles", w.mesh.num_cells() - w.own_triangles},
          {"keys_requested", w.keys_requested}, {"bytes_sent", w.bytes_sent},
          {"guard_shortened", slabs.stats().guard_shortened},
          {"seconds", timer.seconds()}, {"peak_rss_mib", peak_rss_mib()}};
}

}  // namespace

void write_labels_pieces(const LabelsJob& job, generate::LabelSlabs& slabs, const ImageGrid& header,
                         std::pair<Id, Id> rows, StageTimer& timer) {
  const Id halo = generate::LabelSlabs::halo_rows(job.options);
  generate::LabelPiece piece;
  distributed::agreed([&] {
    timer.run("labels", [&] {
      naming_input(job, [&] {
        slabs.generate_with_halo(halo);
        piece = slabs.finish_piece();
      });
    });
  });
  timer.add("read", slabs.stream_stats().read);
  distributed::OwnPiece w = timer.run("number", [&] {
    return distributed::own_piece(
        {piece.mesh, piece.ghost_face, piece.order_key, piece.row, piece.segments, piece.history_key}, rows);
  });
  nlohmann::json pairs = job.common.report_path.empty() ? nlohmann::json::array() : pair_shares(piece, rows);
  piece = generate::LabelPiece{};
  timer.run("write", [&] {
    std::vector<io::UInt64PointArray> history;
    if (job.options.history) history.push_back({"history_key", &w.history_key});
    write_piece_files(w.mesh, w.ids, io::PieceGhosts{std::move(w.point_ghosts), std::move(w.cell_ghosts)}, job.output,
                      history);
  });
  nlohmann::json per_rank = gather_rank_entries(rank_entry(rows, slabs, w, std::move(pairs), timer));
  if (distributed::rank() == 0)
    report_pieces(job, header, slabs.stats(), w.total_points, std::move(per_rank), halo, timer);
}

}  // namespace keymesh::cli
