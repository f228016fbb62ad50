// Distributed KEY-REDUCE of point keys (keymesh/distributed/key_exchange.hpp).
#include "keymesh/distributed/key_exchange.hpp"

#if defined(KEYMESH_HAVE_MPI)

#include "mpi_library.hpp"

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

namespace {

// Where this rank's keys fall: bound[s * (P + 1) + q] = the first local key
// >= first_key(s, q) (binary search among the sorted keys).
struct KeyRanges {
  int ranks = 1;
  std::vector<std::size_t> bound;
  std::size_t at(int s, int q) const { return bound[static_cast<std::size_t>(s) * (ranks + 1) + q]; }
};

KeyRanges find_ranges(std::span<const std::uint64_t> keys, int segments, int P, int r,
                      const std::function<std::uint64_t(int, int)>& first_key) {
  KeyRanges kr;
  kr.ranks = P;
  std::vector<std::uint64_t> range(static_cast<std::size_t>(segments) * (P + 1));
  kr.bound.resize(range.size());
  for (int s = 0; s < segments; ++s)
    for (int q = 0; q <= P; ++q) {
      const std::size_t i = static_cast<std::size_t>(s) * (P + 1) + q;
      range[i] = first_key(s, q);
      if (i > 0 && range[i] < range[i - 1])
        throw InputError("distributed KEY-REDUCE: key ranges do not ascend at segment " + std::to_string(s) +
                         ", rank " + std::to_string(q));
      kr.bound[i] = static_cast<std::size_t>(std::lower_bound(keys.begin(), keys.end(), range[i]) - keys.begin());
    }
  if (kr.bound.front() != 0 || kr.bound.back() != keys.size())
    throw InputError("distributed KEY-REDUCE: rank " + std::to_string(r) + " holds keys outside every segment");
  return kr;
}

// Every rank learns how many keys each rank owns per segment; global ids go
// segment after segment, rank order within a segment (key order, since
// ownership is by key range in rank order). Then this rank numbers the keys
// it owns: ascending keys, ascending ids.
void number_owned(GlobalNumbering& g, const KeyRanges& kr, int r) {
  const int P = g.ranks, segments = g.segments;
  std::vector<long long> mine(static_cast<std::size_t>(segments), 0);
  for (int s = 0; s < segments; ++s) mine[s] = static_cast<long long>(kr.at(s, r + 1) - kr.at(s, r));
  g.counts.assign(static_cast<std::size_t>(P) * segments, 0);
  mpi().Allgather(mine.data(), segments, mpi().long_long, g.counts.data(), segments, mpi().long_long, mpi().comm_world);
  g.first_ids.assign(static_cast<std::size_t>(segments) * P, 0);
  long long total = 0;
  for (int s = 0; s < segments; ++s)
    for (int q = 0; q < P; ++q) {
      g.first_ids[static_cast<std::size_t>(s) * P + q] = total;
      total += g.counts[static_cast<std::size_t>(q) * segments + s];
    }
  g.total = total;
  for (int s = 0; s < segments; ++s) {
    const std::uint64_t first = static_cast<std::uint64_t>(g.first_id(s, r));
    for (std::size_t p = kr.at(s, r), e = kr.at(s, r + 1); p < e; ++p) {
      g.ids[p] = first + (p - kr.at(s, r));
      g.owned[p] = 1;
    }
  }
}

// The all-to-all of the keys held but not owned (few: the shared planes):
// who sends what to whom, and which local key each message slot stands for.
struct Routing {
  std::vector<int> send_counts, recv_counts, send_displs, recv_displs;
  std::vector<std::size_t> asked;     // local key of each request sent
  std::vector<std::size_t> answered;  // local key of each request received
  std::size_t sent() const { return asked.size(); }
  std::size_t received() const { return answered.size(); }

  // The same all-to-all for `bytes` bytes per slot, forward (requests) or back (replies).
  void exchange(const void* out, void* in, std::size_t bytes, bool forward) const {
    auto scaled = [&](const std::vector<int>& v) {
      std::vector<int> o(v.size());
      for (std::size_t q = 0; q < v.size(); ++q) o[q] = checked_int(static_cast<std::size_t>(v[q]) * bytes, "exchanged values");
      return o;
    };
    const auto& sc = forward ? send_counts : recv_counts;
    const auto& sd = forward ? send_displs : recv_displs;
    const auto& rc = forward ? recv_counts : send_counts;
    const auto& rd = forward ? recv_displs : send_displs;
    mpi().Alltoallv(out, scaled(sc).data(), scaled(sd).data(), mpi().byte, in, scaled(rc).data(), scaled(rd).data(),
                    mpi().byte, mpi().comm_world);
  }
};

// Sends every key held but not owned to its owner; returns the routing and
// the keys received (in sender rank order).
Routing route_foreign_keys(std::span<const std::uint64_t> keys, const KeyRanges& kr, int segments, int r,
                           std::vector<std::uint64_t>& incoming) {
  const int P = kr.ranks;
  Routing rt;
  rt.send_counts.assign(static_cast<std::size_t>(P), 0);
  rt.recv_counts.assign(static_cast<std::size_t>(P), 0);
  for (int s = 0; s < segments; ++s)
    for (int q = 0; q < P; ++q)
      if (q != r) rt.send_counts[static_cast<std::size_t>(q)] += static_cast<int>(kr.at(s, q + 1) - kr.at(s, q));
  mpi().Alltoall(rt.send_counts.data(), 1, mpi().int_, rt.recv_counts.data(), 1, mpi().int_, mpi().comm_world);
  rt.send_displs = displacements(rt.send_counts, "requested keys");
  rt.recv_displs = displacements(rt.recv_counts, "requested keys");
  std::size_t n_send = 0, n_recv = 0;
  for (int c : rt.send_counts) n_send += static_cast<std::size_t>(c);
  for (int c : rt.recv_counts) n_recv += static_cast<std::size_t>(c);
  std::vector<std::uint64_t> request(n_send);
  rt.asked.resize(n_send);
  std::vector<int> fill(rt.send_displs);
  for (int s = 0; s < segments; ++s)
    for (int q = 0; q < P; ++q)
      if (q != r)
        for (std::size_t p = kr.at(s, q), e = kr.at(s, q + 1); p < e; ++p) {
          const std::size_t slot = static_cast<std::size_t>(fill[static_cast<std::size_t>(q)]++);
          request[slot] = keys[p];
          rt.asked[slot] = p;
        }
  incoming.resize(n_recv);
  rt.exchange(request.data(), incoming.data(), sizeof(std::uint64_t), true);
  rt.answered.resize(n_recv);
  return rt;
}

// The merge of the values: each copy's partial value goes to the owner,
// which merges them into its own in sender rank order (fixed, whatever the
// timing), then sends the result back to every copy.
std::uint64_t merge_values(const Routing& rt, const ValueMerge& v) {
  const std::size_t b = v.bytes;
  auto* base = static_cast<unsigned char*>(v.values);
  std::vector<unsigned char> partial(rt.sent() * b), received(rt.received() * b);
  for (std::size_t i = 0; i < rt.sent(); ++i) std::copy_n(base + rt.asked[i] * b, b, partial.begin() + i * b);
  rt.exchange(partial.data(), received.data(), b, true);
  for (std::size_t i = 0; i < rt.received(); ++i) v.merge(base + rt.answered[i] * b, received.data() + i * b);
  for (std::size_t i = 0; i < rt.received(); ++i) std::copy_n(base + rt.answered[i] * b, b, received.begin() + i * b);
  rt.exchange(received.data(), partial.data(), b, false);
  for (std::size_t i = 0; i < rt.sent(); ++i) std::copy_n(partial.begin() + i * b, b, base + rt.asked[i] * b);
  return b * (rt.sent() + rt.received());
}

}  // namespace

GlobalNumbering number_keys(std::span<const std::uint64_t> keys, int segments,
                            const std::function<std::uint64_t(int segment, int rank)>& first_key,
                            const ValueMerge* values) {
  int P = 1, r = 0;
  mpi().Comm_size(mpi().comm_world, &P);
  mpi().Comm_rank(mpi().comm_world, &r);
  GlobalNumbering g;
  g.ranks = P;
  g.segments = segments;
  g.ids.assign(keys.size(), 0);
  g.owned.assign(keys.size(), 0);
  const KeyRanges kr = find_ranges(keys, segments, P, r, first_key);
  number_owned(g, kr, r);
  std::vector<std::uint64_t> incoming;
  Routing rt = route_foreign_keys(keys, kr, segments, r, incoming);
  // The owners answer with the keys' global ids (binary search among their
  // ascending keys).
  std::vector<std::uint64_t> answer(rt.received());
  for (std::size_t i = 0; i < rt.received(); ++i) {
    const auto it = std::lower_bound(keys.begin(), keys.end(), incoming[i]);
    const std::size_t p = static_cast<std::size_t>(it - keys.begin());
    if (it == keys.end() || *it != incoming[i] || !g.owned[p])
      throw InputError("distributed KEY-REDUCE: rank " + std::to_string(r) + " owns key " +
                       std::to_string(incoming[i]) + " but has no point with it (did the ranks read different inputs?)");
    answer[i] = g.ids[p];
    rt.answered[i] = p;
  }
  const std::uint64_t value_bytes = values ? merge_values(rt, *values) : 0;
  std::vector<std::uint64_t> reply(rt.sent());
  rt.exchange(answer.data(), reply.data(), sizeof(std::uint64_t), false);
  for (std::size_t i = 0; i < rt.sent(); ++i) g.ids[rt.asked[i]] = reply[i];
  g.keys_requested = rt.sent();
  g.bytes_sent = 8 * (rt.sent() + rt.received()) + value_bytes +
                 sizeof(long long) * static_cast<std::uint64_t>(segments) * (P - 1) +
                 sizeof(int) * static_cast<std::uint64_t>(P - 1);
  return g;
}

}  // namespace keymesh::distributed

#endif
