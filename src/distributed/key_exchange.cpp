// Distributed KEY-REDUCE of point keys (keymesh/distributed/key_exchange.hpp).
#include "keymesh/distributed/key_exchange.hpp"

#if defined(KEYMESH_HAVE_MPI)

#include <mpi.h>

#include <algorithm>
#include <limits>
#include <string>

#include "keymesh/core/error.hpp"

namespace keymesh::distributed {

namespace {

int checked_int(std::size_t n, const char* what) {
  if (n > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw LimitError(std::string("distributed KEY-REDUCE: ") + what + " exceed MPI's 2^31 - 1 elements per message");
  return static_cast<int>(n);
}

// Displacements of an all-to-all from its counts.
std::vector<int> displacements(const std::vector<int>& counts, const char* what) {
  std::vector<int> d(counts.size());
  std::size_t at = 0;
  for (std::size_t q = 0; q < counts.size(); ++q) {
    d[q] = checked_int(at, what);
    at += static_cast<std::size_t>(counts[q]);
  }
  checked_int(at, what);
  return d;
}

}  // namespace

GlobalNumbering number_keys(std::span<const std::uint64_t> keys, int segments,
                            const std::function<int(std::uint64_t)>& segment_of,
                            const std::function<int(std::uint64_t)>& owner_of) {
  int P = 1, r = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &P);
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  const std::size_t n = keys.size();
  GlobalNumbering g;
  g.ranks = P;
  g.segments = segments;
  g.ids.assign(n, 0);
  g.owned.assign(n, 0);

  // 1. Count the keys this rank owns per segment; every rank learns all counts.
  std::vector<int> owner(n);
  std::vector<long long> mine(static_cast<std::size_t>(segments), 0);
  for (std::size_t p = 0; p < n; ++p) {
    owner[p] = owner_of(keys[p]);
    if (owner[p] < 0 || owner[p] >= P)
      throw InputError("distributed KEY-REDUCE: key " + std::to_string(keys[p]) + " has no owner rank");
    if (owner[p] == r) {
      g.owned[p] = 1;
      ++mine[static_cast<std::size_t>(segment_of(keys[p]))];
    }
  }
  g.counts.assign(static_cast<std::size_t>(P) * segments, 0);
  MPI_Allgather(mine.data(), segments, MPI_LONG_LONG, g.counts.data(), segments, MPI_LONG_LONG, MPI_COMM_WORLD);
  // Global ids: segment after segment, rank order within a segment (key
  // order, since ownership is by key range in rank order).
  g.first_ids.assign(static_cast<std::size_t>(segments) * P, 0);
  long long at = 0;
  for (int s = 0; s < segments; ++s)
    for (int q = 0; q < P; ++q) {
      g.first_ids[static_cast<std::size_t>(s) * P + q] = at;
      at += g.counts[static_cast<std::size_t>(q) * segments + s];
    }
  g.total = at;

  // 2. Number the owned keys: ascending keys give ascending ids.
  {
    std::vector<long long> next(static_cast<std::size_t>(segments));
    for (int s = 0; s < segments; ++s) next[s] = g.first_id(s, r);
    for (std::size_t p = 0; p < n; ++p)
      if (g.owned[p]) g.ids[p] = static_cast<std::uint64_t>(next[static_cast<std::size_t>(segment_of(keys[p]))]++);
  }

  // 3. Route every key held but not owned to its owner (all-to-all by key
  //    range), which answers with the key's global id.
  std::vector<int> send_counts(static_cast<std::size_t>(P), 0), recv_counts(static_cast<std::size_t>(P), 0);
  for (std::size_t p = 0; p < n; ++p)
    if (!g.owned[p]) ++send_counts[static_cast<std::size_t>(owner[p])];
  MPI_Alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  const std::vector<int> send_displs = displacements(send_counts, "requested keys");
  const std::vector<int> recv_displs = displacements(recv_counts, "requested keys");
  std::size_t n_send = 0, n_recv = 0;
  for (int c : send_counts) n_send += static_cast<std::size_t>(c);
  for (int c : recv_counts) n_recv += static_cast<std::size_t>(c);
  std::vector<std::uint64_t> request(n_send);
  std::vector<std::size_t> asked(n_send);  // local point of each request
  {
    std::vector<int> fill(send_displs);
    for (std::size_t p = 0; p < n; ++p)
      if (!g.owned[p]) {
        const int at_q = fill[static_cast<std::size_t>(owner[p])]++;
        request[static_cast<std::size_t>(at_q)] = keys[p];
        asked[static_cast<std::size_t>(at_q)] = p;
      }
  }
  std::vector<std::uint64_t> incoming(n_recv);
  MPI_Alltoallv(request.data(), send_counts.data(), send_displs.data(), MPI_UINT64_T, incoming.data(),
                recv_counts.data(), recv_displs.data(), MPI_UINT64_T, MPI_COMM_WORLD);
  // Answer: binary search among this rank's (ascending) keys.
  std::vector<std::uint64_t> answer(n_recv);
  for (std::size_t i = 0; i < n_recv; ++i) {
    const auto it = std::lower_bound(keys.begin(), keys.end(), incoming[i]);
    const std::size_t p = static_cast<std::size_t>(it - keys.begin());
    if (it == keys.end() || *it != incoming[i] || !g.owned[p])
      throw InputError("distributed KEY-REDUCE: rank " + std::to_string(r) + " owns key " +
                       std::to_string(incoming[i]) + " but has no point with it (did the ranks read different inputs?)");
    answer[i] = g.ids[p];
  }
  std::vector<std::uint64_t> reply(n_send);
  MPI_Alltoallv(answer.data(), recv_counts.data(), recv_displs.data(), MPI_UINT64_T, reply.data(),
                send_counts.data(), send_displs.data(), MPI_UINT64_T, MPI_COMM_WORLD);
  for (std::size_t i = 0; i < n_send; ++i) g.ids[asked[i]] = reply[i];
  g.keys_requested = n_send;
  g.bytes_sent = 8 * (n_send + n_recv) + sizeof(long long) * static_cast<std::uint64_t>(segments) * (P - 1) +
                 sizeof(int) * static_cast<std::uint64_t>(P - 1);
  return g;
}

}  // namespace keymesh::distributed

#endif
