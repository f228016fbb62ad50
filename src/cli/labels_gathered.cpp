// `mpirun -np P keymesh labels VOLUME -o OUT` into one file (not .pvtp):
// every rank makes, smooths and coarsens its rows plus halo rows as for
// pieces (labels_pieces.cpp, LabelSlabs::generate_with_halo), keeps its
// share (distributed/halo_piece.hpp), and only those finished shares are
// gathered: rank 0 puts them together by global id
// (distributed/gather_pieces.hpp) and writes the one process's file byte
// for byte. Rank 0 never holds the fine surfaces of more than its rows and
// halo.
//
// The one process writes the triangles label by label (the "label" cell
// field, where the mesh has one: per label, and discrete MC's network),
// and within a label row after row; surface nets' network row after row.
// So a triangle's group is its label's place among all ranks' labels.
#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "labels_job.hpp"
#include "rank_entries.hpp"
#include "keymesh/distributed/gather_pieces.hpp"
#include "keymesh/distributed/halo_piece.hpp"
#include "keymesh/distributed/mpi.hpp"

namespace keymesh::cli {

namespace {

// Collective: each own triangle's group (its label's place among every
// rank's labels; 0 without a "label" cell field), and how many groups.
std::vector<std::uint32_t> own_groups(const generate::LabelPiece& piece, std::uint32_t& groups) {
  const Field* label = piece.mesh.find_cell_field("label");
  std::vector<float> mine;
  for (Id c = 0; label && c < piece.mesh.num_cells(); ++c)
    if (!piece.ghost_face[static_cast<std::size_t>(c)]) mine.push_back(label->values[static_cast<std::size_t>(c)]);
  std::sort(mine.begin(), mine.end());
  mine.erase(std::unique(mine.begin(), mine.end()), mine.end());
  std::vector<std::byte> bytes(mine.size() * sizeof(float));
  if (!bytes.empty()) std::memcpy(bytes.data(), mine.data(), bytes.size());
  std::vector<float> all;
  for (const auto& b : distributed::all_gather_bytes(bytes)) {
    const std::size_t at = all.size();
    all.resize(at + b.size() / sizeof(float));
    if (!b.empty()) std::memcpy(all.data() + at, b.data(), b.size());
  }
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  groups = static_cast<std::uint32_t>(std::max<std::size_t>(all.size(), 1));
  std::vector<std::uint32_t> out;
  for (Id c = 0; c < piece.mesh.num_cells(); ++c) {
    if (piece.ghost_face[static_cast<std::size_t>(c)]) continue;
    const auto g = label ? std::lower_bound(all.begin(), all.end(), label->values[static_cast<std::size_t>(c)]) -
                               all.begin()
                         : 0;
    out.push_back(static_cast<std::uint32_t>(g));
  }
  return out;
}

// This rank's entry of the report.
nlohmann::json rank_entry(std::pair<Id, Id> rows, const generate::LabelSlabs& slabs, const distributed::OwnPiece& w) {
  return {{"first_row", rows.first}, {"rows", rows.second - rows.first},
          {"halo_rows", slabs.stream_stats().halo_rows}, {"slabs", slabs.stream_stats().slabs},
          {"points", w.mesh.num_points()}, {"points_owned", w.points_owned},
          {"triangles", w.own_triangles}, {"peak_rss_mib", peak_rss_mib()}};
}

}  // namespace

void write_labels_gathered(const LabelsJob& job, generate::LabelSlabs& slabs, const ImageGrid& header,
                           std::pair<Id, Id> rows, StageTimer& timer) {
  generate::LabelPiece piece;
  distributed::agreed([&] {
    timer.run("labels", [&] {
      naming_input(job, [&] {
        slabs.generate_with_halo(generate::LabelSlabs::halo_rows(job.options));
        piece = slabs.finish_piece();
      });
    });
  });
  timer.add("read", slabs.stream_stats().read);
  std::uint32_t groups = 1;
  const std::vector<std::uint32_t> group = own_groups(piece, groups);
  const distributed::OwnPiece w = timer.run("number", [&] {
    return distributed::own_piece(
        {piece.mesh, piece.ghost_face, piece.order_key, piece.row, piece.segments, piece.history_key}, rows);
  });
  piece = generate::LabelPiece{};
  std::vector<std::uint64_t> history_key;
  SurfaceMesh mesh;
  distributed::agreed([&] {  // rank 0's failure (after the collective) is every rank's
    mesh = timer.run("gather", [&] {
      return distributed::gather_pieces(w, group, groups, job.options.history ? &history_key : nullptr);
    });
  });
  const nlohmann::json per_rank = gather_rank_entries(rank_entry(rows, slabs, w));
  distributed::agreed([&] {
    if (distributed::rank() != 0) return;
    nlohmann::json r;
    r["dims"] = header.dims;
    r["scalar_type"] = scalar_type_name(header.type);
    if (job.memory_limit) r["memory_limit"] = job.memory_limit;
    r["ranks"] = static_cast<int>(per_rank.size());
    r["distributed"] = {{"ranks", static_cast<int>(per_rank.size())}, {"output", "gathered"},
                        {"halo_rows", generate::LabelSlabs::halo_rows(job.options)}, {"per_rank", per_rank}};
    // The soup and the fine triangles were never whole on one rank: rank
    // 0's counts hold its halo rows (the fold guard's too), so the report
    // leaves them out.
    generate::LabelStats stats = slabs.stats();
    stats.soup_corners = -1;
    stats.triangles_before_coarsening = -1;
    stats.guard_shortened = -1;
    write_labels_outputs(job, mesh, stats, std::move(r), timer, history_key);
  });
}

}  // namespace keymesh::cli
