// The MPI environment (keymesh/distributed/mpi.hpp) over a real MPI.
#include "keymesh/distributed/mpi.hpp"

#if defined(KEYMESH_HAVE_MPI)

#include <algorithm>
#include <atomic>
#include <climits>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/core/loadable_module.hpp"
#include "mpi_library.hpp"

namespace keymesh::distributed {

namespace {

std::atomic<const KeymeshMpiApi*> opened{nullptr};

bool initialized() {
  if (!mpi_opened()) return false;
  int init = 0, fin = 0;
  mpi().Initialized(&init);
  mpi().Finalized(&fin);
  return init && !fin;
}

}  // namespace

const KeymeshMpiApi& mpi() {
  // Global: Open MPI's components (which libmpi dlopens) look for libmpi's
  // and libopen-pal's symbols in the global scope.
  static const KeymeshMpiApi& api = loadable_module_table<KeymeshMpiApi>(
      KEYMESH_MPI_MODULE_FILE, kKeymeshMpiEntry, kKeymeshMpiApiVersion, "a run under an MPI launcher",
      ModuleScope::Global);
  opened.store(&api, std::memory_order_release);
  return api;
}

bool mpi_opened() { return opened.load(std::memory_order_acquire) != nullptr; }

bool compiled() { return true; }

void init(int* argc, char*** argv) {
  if (!launched_by_mpi() || initialized()) return;
  // Only the main thread calls MPI; OpenMP threads work between the calls.
  int provided = 0;
  mpi().Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
}

void finalize() {
  if (initialized()) mpi().Finalize();
}

int rank() {
  int r = 0;
  if (initialized()) mpi().Comm_rank(mpi().comm_world, &r);
  return r;
}

int size() {
  int s = 1;
  if (initialized()) mpi().Comm_size(mpi().comm_world, &s);
  return s;
}

void abort_all(int code) {
  if (initialized()) mpi().Abort(mpi().comm_world, code);
  std::exit(code);
}

bool all_ok(bool ok) {
  if (!initialized()) return ok;
  int mine = ok ? 1 : 0, all = 0;
  mpi().Allreduce(&mine, &all, 1, mpi().int_, mpi().min, mpi().comm_world);
  return all == 1;
}

std::vector<std::vector<std::byte>> all_gather_bytes(const std::vector<std::byte>& mine) {
  if (!initialized()) return {mine};
  const int ranks = size();
  long long n = static_cast<long long>(mine.size());
  std::vector<long long> sizes(static_cast<std::size_t>(ranks));
  mpi().Allgather(&n, 1, mpi().long_long, sizes.data(), 1, mpi().long_long, mpi().comm_world);
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
  mpi().Allgatherv(mine.data(), static_cast<int>(n), mpi().byte, all.data(), counts.data(), displs.data(), mpi().byte,
                   mpi().comm_world);
  std::vector<std::vector<std::byte>> out(static_cast<std::size_t>(ranks));
  for (int q = 0; q < ranks; ++q)
    out[static_cast<std::size_t>(q)].assign(all.begin() + displs[static_cast<std::size_t>(q)],
                                            all.begin() + displs[static_cast<std::size_t>(q)] +
                                                counts[static_cast<std::size_t>(q)]);
  return out;
}

std::string first_error(const std::string& mine) {
  if (!initialized()) return mine;
  const auto* b = reinterpret_cast<const std::byte*>(mine.data());
  for (const auto& e : all_gather_bytes(std::vector<std::byte>(b, b + mine.size())))
    if (!e.empty()) return std::string(reinterpret_cast<const char*>(e.data()), e.size());
  return {};
}

void gather_chunks(const std::function<bool(std::vector<std::byte>&)>& next,
                   const std::function<void(int, const std::vector<std::byte>&)>& take) {
  std::vector<std::byte> chunk;
  if (!initialized() || rank() == 0) {
    while (next(chunk)) take(0, chunk);
    if (!initialized()) return;
  }
  constexpr std::uint64_t kPiece = 1u << 30;  // MPI counts are int
  constexpr std::uint64_t kDone = ~std::uint64_t{0};
  if (rank() != 0) {
    auto send = [&](std::uint64_t n) {
      mpi().Send(&n, 1, mpi().uint64, 0, 0, mpi().comm_world);
      for (std::uint64_t at = 0; n != kDone && at < n; at += kPiece)
        mpi().Send(chunk.data() + at, static_cast<int>(std::min(kPiece, n - at)), mpi().byte, 0, 1, mpi().comm_world);
    };
    while (next(chunk)) send(chunk.size());
    send(kDone);
    return;
  }
  for (int q = 1; q < size(); ++q)
    for (;;) {
      std::uint64_t n = 0;
      mpi().Recv(&n, 1, mpi().uint64, q, 0, mpi().comm_world, MPI_STATUS_IGNORE);
      if (n == kDone) break;
      chunk.resize(static_cast<std::size_t>(n));
      for (std::uint64_t at = 0; at < n; at += kPiece)
        mpi().Recv(chunk.data() + at, static_cast<int>(std::min(kPiece, n - at)), mpi().byte, q, 1, mpi().comm_world,
                   MPI_STATUS_IGNORE);
      take(q, chunk);
    }
}

std::vector<std::vector<std::byte>> gather_bytes(const std::vector<std::byte>& mine) {
  if (!initialized()) return {mine};
  const int me = rank(), ranks = size();
  constexpr std::uint64_t kPiece = 1u << 30;  // MPI counts are int
  if (me != 0) {
    const std::uint64_t n = mine.size();
    mpi().Send(&n, 1, mpi().uint64, 0, 0, mpi().comm_world);
    for (std::uint64_t at = 0; at < n; at += kPiece)
      mpi().Send(mine.data() + at, static_cast<int>(std::min(kPiece, n - at)), mpi().byte, 0, 1, mpi().comm_world);
    return {};
  }
  std::vector<std::vector<std::byte>> out(static_cast<std::size_t>(ranks));
  out[0] = mine;
  for (int q = 1; q < ranks; ++q) {
    std::uint64_t n = 0;
    mpi().Recv(&n, 1, mpi().uint64, q, 0, mpi().comm_world, MPI_STATUS_IGNORE);
    auto& bytes = out[static_cast<std::size_t>(q)];
    bytes.resize(static_cast<std::size_t>(n));
    for (std::uint64_t at = 0; at < n; at += kPiece)
      mpi().Recv(bytes.data() + at, static_cast<int>(std::min(kPiece, n - at)), mpi().byte, q, 1, mpi().comm_world,
                 MPI_STATUS_IGNORE);
  }
  return out;
}

}  // namespace keymesh::distributed

#endif
