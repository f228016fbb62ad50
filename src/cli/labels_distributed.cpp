// `mpirun -np P keymesh labels VOLUME -o OUT`: every rank reads and
// contours its rows of the padded volume (generate/labels_stream.hpp's passes,
// streamed in slabs too with --memory-limit); the ranks share their distinct
// labels and counts. Then every rank makes its share with halo rows and
// either writes its own piece of OUT.pvtp (labels_pieces.cpp: nothing
// gathered) or, for any other file, sends its finished share to rank 0,
// which puts the shares together and writes one file, byte-identical to the
// single-process run (labels_gathered.cpp).
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
  if (into_pieces)
    write_labels_pieces(job, *slabs, source->header(), rows_of(total_rows, rank, ranks), timer);
  else
    write_labels_gathered(job, *slabs, source->header(), rows_of(total_rows, rank, ranks), timer);
  return 0;
}

}  // namespace keymesh::cli
