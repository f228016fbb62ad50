// The MPI environment (keymesh/distributed/mpi.hpp) over a real MPI.
#include "keymesh/distributed/mpi.hpp"

#if defined(KEYMESH_HAVE_MPI)

#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "keymesh/core/error.hpp"

namespace keymesh::distributed {

namespace {
bool initialized() {
  int init = 0, fin = 0;
  MPI_Initialized(&init);
  MPI_Finalized(&fin);
  return init && !fin;
}
}  // namespace

bool compiled() { return true; }

void init(int* argc, char*** argv) {
  if (!launched_by_mpi() || initialized()) return;
  // Only the main thread calls MPI; OpenMP threads work between the calls.
  int provided = 0;
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
}

void finalize() {
  if (initialized()) MPI_Finalize();
}

int rank() {
  int r = 0;
  if (initialized()) MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int size() {
  int s = 1;
  if (initialized()) MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

void abort_all(int code) {
  if (initialized()) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

bool all_ok(bool ok) {
  if (!initialized()) return ok;
  int mine = ok ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  return all == 1;
}

std::vector<std::vector<std::byte>> all_gather_bytes(const std::vector<std::byte>& mine) {
  if (!initialized()) return {mine};
  const int ranks = size();
  long long n = static_cast<long long>(mine.size());
  std::vector<long long> sizes(static_cast<std::size_t>(ranks));
  MPI_Allgather(&n, 1, MPI_LONG_LONG, sizes.data(), 1, MPI_LONG_LONG, MPI_COMM_WORLD);
  std::vector<int> counts(static_cast<std::size_t>(ranks)), displs(static_cast<std::size_t>(ranks));
  long long total = 0;
  for (int q = 0; q < ranks; ++q) {
    displs[static_cast<std::size_t>(q)] = static_cast<int>(std::min<long long>(total, INT_MAX));
    counts[static_cast<std::size_t>(q)] = static_cast<int>(std::min<long long>(sizes[static_cast<std::size_t>(q)], INT_MAX));
    total += sizes[static_cast<std::size_t>(q)];
  }
  if (total > INT_MAX)  // every rank sees the same sizes: all refuse alike
    throw LimitError("distributed: " + std::to_string(total) + " bytes to share among the ranks exceed 2^31 - 1");
  std::vector<std::byte> all(static_cast<std::size_t>(total));
  MPI_Allgatherv(mine.data(), static_cast<int>(n), MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE,
                 MPI_COMM_WORLD);
  std::vector<std::vector<std::byte>> out(static_cast<std::size_t>(ranks));
  for (int q = 0; q < ranks; ++q)
    out[static_cast<std::size_t>(q)].assign(all.begin() + displs[static_cast<std::size_t>(q)],
                                            all.begin() + displs[static_cast<std::size_t>(q)] +
                                                counts[static_cast<std::size_t>(q)]);
  return out;
}

std::vector<std::vector<std::byte>> gather_bytes(const std::vector<std::byte>& mine) {
  if (!initialized()) return {mine};
  const int me = rank(), ranks = size();
  constexpr std::uint64_t kPiece = 1u << 30;  // MPI counts are int
  if (me != 0) {
    const std::uint64_t n = mine.size();
    MPI_Send(&n, 1, MPI_UINT64_T, 0, 0, MPI_COMM_WORLD);
    for (std::uint64_t at = 0; at < n; at += kPiece)
      MPI_Send(mine.data() + at, static_cast<int>(std::min(kPiece, n - at)), MPI_BYTE, 0, 1, MPI_COMM_WORLD);
    return {};
  }
  std::vector<std::vector<std::byte>> out(static_cast<std::size_t>(ranks));
  out[0] = mine;
  for (int q = 1; q < ranks; ++q) {
    std::uint64_t n = 0;
    MPI_Recv(&n, 1, MPI_UINT64_T, q, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    auto& bytes = out[static_cast<std::size_t>(q)];
    bytes.resize(static_cast<std::size_t>(n));
    for (std::uint64_t at = 0; at < n; at += kPiece)
      MPI_Recv(bytes.data() + at, static_cast<int>(std::min(kPiece, n - at)), MPI_BYTE, q, 1, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
  }
  return out;
}

}  // namespace keymesh::distributed

#endif
