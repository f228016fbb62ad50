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
                            const std::function<std::uint64_t(int segment, int rank)>& first_key,
                            std::vector<float>* sums, int components) {
  if (sums && (components <= 0 || sums->size() != keys.size() * static_cast<std::size_t>(components)))
    throw InputError("distributed KEY-REDUCE: " + std::to_string(sums->size()) + " values for " +
                     std::to_string(keys.size()) + " keys of " + std::to_string(components) + " components");
  int P = 1, r = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &P);
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  const std::size_t n = keys.size();
  GlobalNumbering g;
  g.ranks = P;
  g.segments = segments;
  g.ids.assign(n, 0);
  g.owned.assign(n, 0);

  // 1. The key ranges, found by binary search among this rank's sorted keys:
  //    bound[s * (P + 1) + q] = first local key >= first_key(s, q).
  std::vector<std::uint64_t> range(static_cast<std::size_t>(segments) * (P + 1));
  std::vector<std::size_t> bound(range.size());
  for (int s = 0; s < segments; ++s)
    for (int q = 0; q <= P; ++q) {
      const std::size_t i = static_cast<std::size_t>(s) * (P + 1) + q;
      range[i] = first_key(s, q);
      if (i > 0 && range[i] < range[i - 1])
        throw InputError("distributed KEY-REDUCE: key ranges do not ascend at segment " + std::to_string(s) +
                         ", rank " + std::to_string(q));
      bound[i] = static_cast<std::size_t>(std::lower_bound(keys.begin(), keys.end(), range[i]) - keys.begin());
    }
  if (bound.front() != 0 || bound.back() != n)
    throw InputError("distributed KEY-REDUCE: rank " + std::to_string(r) + " holds keys outside every segment");
  auto at = [&](int s, int q) { return bound[static_cast<std::size_t>(s) * (P + 1) + q]; };

  // 2. Count the keys this rank owns per segment; every rank learns all counts.
  std::vector<long long> mine(static_cast<std::size_t>(segments), 0);
  for (int s = 0; s < segments; ++s) mine[s] = static_cast<long long>(at(s, r + 1) - at(s, r));
  g.counts.assign(static_cast<std::size_t>(P) * segments, 0);
  MPI_Allgather(mine.data(), segments, MPI_LONG_LONG, g.counts.data(), segments, MPI_LONG_LONG, MPI_COMM_WORLD);
  // Global ids: segment after segment, rank order within a segment (key
  // order, since ownership is by key range in rank order).
  g.first_ids.assign(static_cast<std::size_t>(segments) * P, 0);
  long long total = 0;
  for (int s = 0; s < segments; ++s)
    for (int q = 0; q < P; ++q) {
      g.first_ids[static_cast<std::size_t>(s) * P + q] = total;
      total += g.counts[static_cast<std::size_t>(q) * segments + s];
    }
  g.total = total;

  // 3. Number the owned keys: ascending keys, ascending ids.
  for (int s = 0; s < segments; ++s) {
    const std::uint64_t first = static_cast<std::uint64_t>(g.first_id(s, r));
    for (std::size_t p = at(s, r), e = at(s, r + 1); p < e; ++p) {
      g.ids[p] = first + (p - at(s, r));
      g.owned[p] = 1;
    }
  }
  // The owner of every key held but not owned (few: the shared planes).
  std::vector<std::size_t> foreign;
  std::vector<int> owner;
  for (int s = 0; s < segments; ++s)
    for (int q = 0; q < P; ++q)
      if (q != r)
        for (std::size_t p = at(s, q), e = at(s, q + 1); p < e; ++p) {
          foreign.push_back(p);
          owner.push_back(q);
        }

  // 4. Route every key held but not owned to its owner (all-to-all by key
  //    range), which answers with the key's global id.
  std::vector<int> send_counts(static_cast<std::size_t>(P), 0), recv_counts(static_cast<std::size_t>(P), 0);
  for (int q : owner) ++send_counts[static_cast<std::size_t>(q)];
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
    for (std::size_t i = 0; i < foreign.size(); ++i) {
      const int at_q = fill[static_cast<std::size_t>(owner[i])]++;
      request[static_cast<std::size_t>(at_q)] = keys[foreign[i]];
      asked[static_cast<std::size_t>(at_q)] = foreign[i];
    }
  }
  std::vector<std::uint64_t> incoming(n_recv);
  MPI_Alltoallv(request.data(), send_counts.data(), send_displs.data(), MPI_UINT64_T, incoming.data(),
                recv_counts.data(), recv_displs.data(), MPI_UINT64_T, MPI_COMM_WORLD);
  // Answer: binary search among this rank's (ascending) keys.
  std::vector<std::uint64_t> answer(n_recv);
  std::vector<std::size_t> answered(n_recv);  // local point of each incoming key
  for (std::size_t i = 0; i < n_recv; ++i) {
    const auto it = std::lower_bound(keys.begin(), keys.end(), incoming[i]);
    const std::size_t p = static_cast<std::size_t>(it - keys.begin());
    if (it == keys.end() || *it != incoming[i] || !g.owned[p])
      throw InputError("distributed KEY-REDUCE: rank " + std::to_string(r) + " owns key " +
                       std::to_string(incoming[i]) + " but has no point with it (did the ranks read different inputs?)");
    answer[i] = g.ids[p];
    answered[i] = p;
  }
  std::uint64_t value_bytes = 0;
  if (sums) {
    // The merge: each copy's partial sum goes to the owner, which adds them
    // to its own in sender rank order (fixed, whatever the timing), then
    // sends the total back to every copy.
    const std::size_t c = static_cast<std::size_t>(components);
    auto scaled = [&](const std::vector<int>& v) {
      std::vector<int> out(v.size());
      for (std::size_t q = 0; q < v.size(); ++q) out[q] = checked_int(static_cast<std::size_t>(v[q]) * c, "merged values");
      return out;
    };
    const std::vector<int> sc = scaled(send_counts), sd = scaled(send_displs), rc = scaled(recv_counts),
                           rd = scaled(recv_displs);
    float* v = sums->data();
    std::vector<float> partial(n_send * c), received(n_recv * c);
    for (std::size_t i = 0; i < n_send; ++i) std::copy_n(v + asked[i] * c, c, partial.begin() + i * c);
    MPI_Alltoallv(partial.data(), sc.data(), sd.data(), MPI_FLOAT, received.data(), rc.data(), rd.data(), MPI_FLOAT,
                  MPI_COMM_WORLD);
    for (std::size_t i = 0; i < n_recv; ++i)
      for (std::size_t k = 0; k < c; ++k) v[answered[i] * c + k] += received[i * c + k];
    for (std::size_t i = 0; i < n_recv; ++i) std::copy_n(v + answered[i] * c, c, received.begin() + i * c);
    MPI_Alltoallv(received.data(), rc.data(), rd.data(), MPI_FLOAT, partial.data(), sc.data(), sd.data(), MPI_FLOAT,
                  MPI_COMM_WORLD);
    for (std::size_t i = 0; i < n_send; ++i) std::copy_n(partial.begin() + i * c, c, v + asked[i] * c);
    value_bytes = 4 * c * (n_send + n_recv);
  }
  std::vector<std::uint64_t> reply(n_send);
  MPI_Alltoallv(answer.data(), recv_counts.data(), recv_displs.data(), MPI_UINT64_T, reply.data(),
                send_counts.data(), send_displs.data(), MPI_UINT64_T, MPI_COMM_WORLD);
  for (std::size_t i = 0; i < n_send; ++i) g.ids[asked[i]] = reply[i];
  g.keys_requested = n_send;
  g.bytes_sent = 8 * (n_send + n_recv) + value_bytes + sizeof(long long) * static_cast<std::uint64_t>(segments) * (P - 1) +
                 sizeof(int) * static_cast<std::uint64_t>(P - 1);
  return g;
}

}  // namespace keymesh::distributed

#endif
