// `mpirun -np P keymesh labels VOLUME -o OUT`: every rank reads and
// contours its rows of the padded volume (generate/labels_stream.hpp's passes,
// streamed in slabs too with --memory-limit); the ranks share their distinct
// labels and counts, rank 0 gathers the pieces, merges them by key, smooths
// and writes one file, byte-identical to the single-process run. Not written:
// .pvtp pieces (smoothing and the per-label surfaces cross the ranks' rows).
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

}  // namespace

int run_distributed_labels(const LabelsJob& job) {
  const int rank = distributed::rank(), ranks = distributed::size();
  const std::string out = job.output;
  if (out.size() >= 5 && out.compare(out.size() - 5, 5, ".pvtp") == 0) {
    if (rank == 0)
      std::fprintf(stderr, "keymesh labels: %s: under mpirun the mesh is gathered on rank 0 into one file; .pvtp "
                           "pieces are not written (smoothing crosses the ranks' slabs): use .vtp\n", out.c_str());
    return 2;
  }
  StageTimer timer;
  // Each step on every rank, then the ranks share their errors: any error
  // ends every rank alike, and rank 0 prints the first one (lowest rank).
  bool ok = true;
  auto step = [&](const char* name, auto&& f) {
    std::string error;
    if (ok) {
      try {
        timer.run(name, [&] { naming_input(job, f); });
      } catch (const std::exception& e) {
        error = e.what();
      }
    }
    const auto* b = reinterpret_cast<const std::byte*>(error.data());
    for (const auto& e : distributed::all_gather_bytes(std::vector<std::byte>(b, b + error.size())))
      if (ok && !e.empty()) {
        if (rank == 0) std::fprintf(stderr, "keymesh: %.*s\n", static_cast<int>(e.size()), reinterpret_cast<const char*>(e.data()));
        ok = false;
      }
    return ok;
  };
  std::unique_ptr<PlaneSource> source;
  std::unique_ptr<generate::LabelSlabs> slabs;
  Id total_rows = 0;
  std::vector<std::vector<std::byte>> pieces;
  const bool done =
      step("open",
           [&] {
             source = io::open_volume_planes(job.input, job.raw_given ? &job.raw : nullptr);
             total_rows = generate::LabelSlabs::total_rows(source->header());
             const std::size_t limit = job.memory_limit ? job.memory_limit : std::numeric_limits<std::size_t>::max();
             slabs = std::make_unique<generate::LabelSlabs>(*source, job.options, limit,
                                                            rows_of(total_rows, rank, ranks));
           }) &&
      step("scan",
           [&] {
             std::vector<std::vector<std::int64_t>> all;
             for (const auto& b : distributed::all_gather_bytes(bytes_of(slabs->distinct_labels())))
               all.push_back(labels_of(b));
             slabs->set_labels(all);
             slabs->set_counts(distributed::all_gather_bytes(slabs->count_labels()));
           }) &&
      step("labels",
           [&] {
             slabs->generate();
             pieces = distributed::gather_bytes(slabs->pieces_bytes());
           });
  if (!done) return 1;
  // Rank 0 merges, smooths and writes; the others wait for its vote.
  if (rank != 0) return step("merge", [] {}) ? 0 : 1;
  const bool written = step("merge", [&] {
    for (int q = 1; q < ranks; ++q) slabs->add_pieces(pieces[static_cast<std::size_t>(q)]);
    const SurfaceMesh mesh = slabs->finish();
    nlohmann::json r;
    r["dims"] = source->header().dims;
    r["scalar_type"] = scalar_type_name(source->header().type);
    if (job.memory_limit) r["memory_limit"] = job.memory_limit;
    nlohmann::json per_rank = nlohmann::json::array();
    for (int q = 0; q < ranks; ++q) {
      const auto [b, e] = rows_of(total_rows, q, ranks);
      per_rank.push_back({{"first_row", b}, {"rows", e - b}, {"piece_bytes", pieces[static_cast<std::size_t>(q)].size()}});
    }
    r["ranks"] = ranks;
    r["distributed"] = {{"ranks", ranks}, {"output", "gathered"}, {"per_rank", per_rank}};
    write_labels_outputs(job, mesh, slabs->stats(), std::move(r), timer);
  });
  return written ? 0 : 1;
}

}  // namespace keymesh::cli
