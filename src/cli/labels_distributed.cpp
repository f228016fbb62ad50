// `mpirun -np P keymesh labels VOLUME -o OUT`: every rank reads and
// contours its rows of the padded volume (generate/labels_stream.hpp's passes,
// streamed in slabs too with --memory-limit); the ranks share their distinct
// labels and counts. Then either every rank writes its own piece of
// OUT.pvtp (labels_pieces.cpp: nothing gathered), or, for any other file,
// rank 0 gathers the pieces, merges them by key, smooths and writes one
// file, byte-identical to the single-process run.
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

#include "labels_job.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/generate/labels/labels_stream.hpp"
#include "keymesh/io/plane_source.hpp"

namespace keymesh::cli {

namespace {

std::vector<std::byte> bytes_of(const std::vector<std::int64_t>& v) {
  std::vector<std::byte> out(v.size() * sizeof(std::int64_t));
  if (!out.empty()) std::memcpy(out.data(), v.data(), out.size());  // empty: data() may be null
  return out;
}

std::vector<std::int64_t> labels_of(const std::vector<std::byte>& b) {
  std::vector<std::int64_t> out(b.size() / sizeof(std::int64_t));
  if (!out.empty()) std::memcpy(out.data(), b.data(), out.size() * sizeof(std::int64_t));  // empty: data() may be null
  return out;
}

// Rows [first, end) of rank q among `ranks`: equal shares of the padded planes.
std::pair<Id, Id> rows_of(Id rows, int q, int ranks) {
  return {rows * q / ranks, rows * (q + 1) / ranks};
}

// Rank 0: every rank's pieces merged by key, smoothed and written.
void write_merged(const LabelsJob& job, generate::LabelSlabs& slabs, const ImageGrid& header,
                  const std::vector<std::vector<std::byte>>& pieces, StageTimer& timer) {
  const int ranks = static_cast<int>(pieces.size());
  const Id total_rows = generate::LabelSlabs::total_rows(header);
  for (int q = 1; q < ranks; ++q) slabs.add_pieces(pieces[static_cast<std::size_t>(q)]);
  std::vector<std::uint64_t> history_key;
  const SurfaceMesh mesh = slabs.finish(&history_key);
  nlohmann::json r;
  r["dims"] = header.dims;
  r["scalar_type"] = scalar_type_name(header.type);
  if (job.memory_limit) r["memory_limit"] = job.memory_limit;
  nlohmann::json per_rank = nlohmann::json::array();
  for (int q = 0; q < ranks; ++q) {
    const auto [b, e] = rows_of(total_rows, q, ranks);
    per_rank.push_back({{"first_row", b}, {"rows", e - b}, {"piece_bytes", pieces[static_cast<std::size_t>(q)].size()}});
  }
  r["ranks"] = ranks;
  r["distributed"] = {{"ranks", ranks}, {"output", "gathered"}, {"per_rank", per_rank}};
  write_labels_outputs(job, mesh, slabs.stats(), std::move(r), timer, history_key);
}

}  // namespace

int run_distributed_labels(const LabelsJob& job) {
  const int rank = distributed::rank(), ranks = distributed::size();
  const std::string out = job.output;
  const bool into_pieces = out.size() >= 5 && out.compare(out.size() - 5, 5, ".pvtp") == 0;
  StageTimer timer;
  // Each step is this rank's own work, then the ranks agree
  // (distributed::agreed): an error on any rank, a slice only the last rank
  // reads included, ends every rank at the same step, said once by rank 0
  // (main.cpp). The collectives run between the steps, never inside one.
  auto step = [&](const char* name, auto&& f) {
    distributed::agreed([&] { timer.run(name, [&] { naming_input(job, f); }); });
  };
  std::unique_ptr<PlaneSource> source;
  std::unique_ptr<generate::LabelSlabs> slabs;
  Id total_rows = 0;
  step("open", [&] {
    source = io::open_volume_planes(job.input, job.raw_given ? &job.raw : nullptr);
    total_rows = generate::LabelSlabs::total_rows(source->header());
    const std::size_t limit = job.memory_limit ? job.memory_limit : std::numeric_limits<std::size_t>::max();
    check_labels_memory(job, source->header(), rows_of(total_rows, rank, ranks));
    slabs = std::make_unique<generate::LabelSlabs>(*source, job.options, limit, rows_of(total_rows, rank, ranks));
  });
  std::vector<std::int64_t> mine;
  step("scan", [&] { mine = slabs->distinct_labels(); });
  std::vector<std::vector<std::int64_t>> all;
  for (const auto& b : distributed::all_gather_bytes(bytes_of(mine))) all.push_back(labels_of(b));
  step("scan", [&] { slabs->set_labels(all); });
  std::vector<std::byte> counts;
  step("scan", [&] { counts = slabs->count_labels(); });
  const std::vector<std::vector<std::byte>> all_counts = distributed::all_gather_bytes(counts);
  step("scan", [&] { slabs->set_counts(all_counts); });
  if (into_pieces) {
    write_labels_pieces(job, *slabs, source->header(), rows_of(total_rows, rank, ranks), timer);
    return 0;
  }
  std::vector<std::byte> my_pieces;
  step("labels", [&] {
    slabs->generate();
    my_pieces = slabs->pieces_bytes();
  });
  const std::vector<std::vector<std::byte>> pieces = distributed::gather_bytes(my_pieces);
  // Rank 0 merges, smooths and writes; the others wait for its vote.
  step("merge", [&] {
    if (rank == 0) write_merged(job, *slabs, source->header(), pieces, timer);
  });
  return 0;
}

}  // namespace keymesh::cli
