// Pieces put together on rank 0 (keymesh/distributed/gather_pieces.hpp).
// Built on gather_bytes and gather_chunks, so it compiles without MPI
// too (a world of one rank: its own piece is the whole).
#include "keymesh/distributed/gather_pieces.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/distributed/mpi.hpp"

namespace keymesh::distributed {

namespace {

template <class T>
void put(std::vector<std::byte>& b, const T& v) {
  const std::size_t at = b.size();
  b.resize(at + sizeof(T));
  std::memcpy(b.data() + at, &v, sizeof(T));
}

template <class T>
T take(const std::byte*& at) {
  T v;
  std::memcpy(&v, at, sizeof(T));
  at += sizeof(T);
  return v;
}

// A point as sent: global id, 1 from its owner (0 from another rank's copy),
// history key (with history), position, point field values.
std::size_t point_record(const SurfaceMesh& m, bool history) {
  std::size_t values = 3;
  for (const Field& f : m.point_fields) values += static_cast<std::size_t>(f.components);
  return 8 + 1 + (history ? 8 : 0) + 4 * values;
}

constexpr std::size_t kChunk = std::size_t{1} << 16;  // points or cells a chunk

// The points rank q sends: those it owns and those of its own triangles
// (a point no owner's triangle uses still comes from the rank whose own
// triangle does: together they are every point of the mesh).
std::vector<std::uint8_t> sent_points(const OwnPiece& w) {
  const SurfaceMesh& m = w.mesh;
  std::vector<std::uint8_t> sent(static_cast<std::size_t>(m.num_points()), 0);
  for (Id c = 0; c < w.own_triangles; ++c)
    for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k) sent[m.connectivity[k]] = 1;
  for (std::size_t p = 0; p < sent.size(); ++p) sent[p] = sent[p] || w.point_ghosts[p] == 0;
  return sent;
}

// The next chunk of the points sent, from point `at` on; false when none is left.
bool points_chunk(const OwnPiece& w, const std::vector<std::uint8_t>& sent, bool history, std::size_t& at,
                  std::vector<std::byte>& out) {
  const SurfaceMesh& m = w.mesh;
  if (at >= sent.size()) return false;
  out.clear();
  const std::size_t end = std::min(sent.size(), at + kChunk);
  for (std::size_t p = at; p < end; ++p) {
    if (!sent[p]) continue;
    put(out, w.ids[p]);
    put(out, static_cast<std::uint8_t>(w.point_ghosts[p] == 0 ? 1 : 0));
    if (history) put(out, w.history_key[p]);
    for (int k = 0; k < 3; ++k) put(out, m.points[3 * p + static_cast<std::size_t>(k)]);
    for (const Field& f : m.point_fields)
      for (int k = 0; k < f.components; ++k) put(out, f.values[static_cast<std::size_t>(f.components) * p + k]);
  }
  at = end;
  return true;
}

// Per group: this rank's own cells and their corners; then 1 when its mesh has polygons.
std::vector<std::byte> counts_bytes(const OwnPiece& w, std::span<const std::uint32_t> own_group,
                                    std::uint32_t groups) {
  std::vector<std::uint64_t> n(2 * static_cast<std::size_t>(groups) + 1, 0);
  for (Id c = 0; c < w.own_triangles; ++c) {
    const std::uint32_t g = own_group[static_cast<std::size_t>(c)];
    if (g >= groups) continue;  // refused by cells_bytes' reader
    n[2 * g] += 1;
    n[2 * g + 1] += w.mesh.cell_end(c) - w.mesh.cell_begin(c);
  }
  n.back() = w.mesh.all_triangles() ? 0 : 1;
  std::vector<std::byte> out(n.size() * sizeof(std::uint64_t));
  std::memcpy(out.data(), n.data(), out.size());
  return out;
}

// The next chunk of own cells, from cell `at` on; false when none is left.
// A cell as sent: group, corners, their global ids (32 bits: the whole
// mesh's point ids, checked by prepare), cell field values.
bool cells_chunk(const OwnPiece& w, std::span<const std::uint32_t> own_group, Id& at, std::vector<std::byte>& out) {
  const SurfaceMesh& m = w.mesh;
  if (at >= w.own_triangles) return false;
  out.clear();
  const Id end = std::min<Id>(w.own_triangles, at + static_cast<Id>(kChunk));
  for (Id c = at; c < end; ++c) {
    put(out, own_group[static_cast<std::size_t>(c)]);
    put(out, static_cast<std::uint32_t>(m.cell_end(c) - m.cell_begin(c)));
    for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k)
      put(out, static_cast<PointIndex>(w.ids[m.connectivity[k]]));
    for (const Field& f : m.cell_fields)
      for (int k = 0; k < f.components; ++k)
        put(out, f.values[static_cast<std::size_t>(f.components) * static_cast<std::size_t>(c) + k]);
  }
  at = end;
  return true;
}

// Rank 0's whole mesh as the ranks' shares arrive. Errors are kept, not
// thrown, until every rank has sent (a throw would leave them waiting).
struct Assembly {
  SurfaceMesh mesh;
  std::vector<std::uint64_t>* history = nullptr;
  std::vector<std::uint8_t> from;      // per point: 0 not yet, 1 a copy, 2 its owner's
  std::vector<std::uint64_t> cell_at;  // per (group, rank): next cell
  std::vector<std::uint64_t> corner_at;
  std::vector<std::uint64_t> corners;  // per cell, with polygons
  bool polygons = false;
  int ranks = 1;
  std::string error;
};

void place_points(Assembly& a, const std::vector<std::byte>& bytes, std::size_t record) {
  if (!a.error.empty()) return;
  SurfaceMesh& m = a.mesh;
  for (const std::byte* at = bytes.data(); at + record <= bytes.data() + bytes.size();) {
    const auto id = take<std::uint64_t>(at);
    const std::uint8_t from = take<std::uint8_t>(at) ? 2 : 1;
    if (id >= a.from.size()) {
      a.error = "gathered pieces: global id " + std::to_string(id) + " past the mesh's " +
                std::to_string(a.from.size()) + " points (internal error)";
      return;
    }
    const bool keep = from > a.from[id];
    a.from[id] = std::max(a.from[id], from);
    if (a.history) {
      const auto key = take<std::uint64_t>(at);
      if (keep) (*a.history)[id] = key;
    }
    for (int k = 0; k < 3; ++k) {
      const auto v = take<float>(at);
      if (keep) m.points[3 * id + static_cast<std::uint64_t>(k)] = v;
    }
    for (Field& f : m.point_fields)
      for (int k = 0; k < f.components; ++k) {
        const auto v = take<float>(at);
        if (keep) f.values[static_cast<std::uint64_t>(f.components) * id + static_cast<std::uint64_t>(k)] = v;
      }
  }
}

void place_cells(Assembly& a, int q, const std::vector<std::byte>& bytes, std::uint32_t groups) {
  if (!a.error.empty()) return;
  SurfaceMesh& m = a.mesh;
  const std::uint64_t n = a.from.size();
  for (const std::byte* at = bytes.data(); at < bytes.data() + bytes.size();) {
    const auto g = take<std::uint32_t>(at);
    const auto corners = take<std::uint32_t>(at);
    if (g >= groups) {
      a.error = "gathered pieces: a triangle of group " + std::to_string(g) + " of " + std::to_string(groups) +
                " (internal error)";
      return;
    }
    const std::size_t slot = static_cast<std::size_t>(g) * static_cast<std::size_t>(a.ranks) + static_cast<std::size_t>(q);
    const std::uint64_t cell = a.cell_at[slot]++;
    std::uint64_t corner = a.corner_at[slot];
    a.corner_at[slot] += corners;
    if (a.polygons) a.corners[cell] = corners;
    for (std::uint32_t k = 0; k < corners; ++k) {
      const auto id = take<PointIndex>(at);
      if (id >= n) a.error = "gathered pieces: a triangle on global id " + std::to_string(id) + " (internal error)";
      m.connectivity[corner++] = static_cast<PointIndex>(id);
    }
    for (Field& f : m.cell_fields)
      for (int k = 0; k < f.components; ++k)
        f.values[static_cast<std::uint64_t>(f.components) * cell + static_cast<std::uint64_t>(k)] = take<float>(at);
  }
}

// Rank 0: the whole mesh's arrays, and where each (group, rank)'s cells go.
void prepare(Assembly& a, const OwnPiece& w, const std::vector<std::vector<std::byte>>& counts,
             std::uint32_t groups) {
  if (w.total_points > static_cast<long long>(std::numeric_limits<PointIndex>::max())) {
    a.error = "gathered pieces: " + std::to_string(w.total_points) + " points exceed 32-bit point ids";
    return;  // thrown once every rank has sent
  }
  const auto total = static_cast<std::size_t>(w.total_points);
  a.ranks = static_cast<int>(counts.size());
  a.from.assign(total, 0);
  a.mesh.points.resize(3 * total);
  for (const Field& f : w.mesh.point_fields) {
    a.mesh.point_fields.push_back(Field{f.name, f.components, {}});
    a.mesh.point_fields.back().values.resize(static_cast<std::size_t>(f.components) * total);
  }
  const std::size_t slots = static_cast<std::size_t>(groups) * counts.size();
  a.cell_at.assign(slots, 0);
  a.corner_at.assign(slots, 0);
  std::uint64_t cells = 0, corners = 0;
  for (std::uint32_t g = 0; g < groups; ++g)
    for (std::size_t q = 0; q < counts.size(); ++q) {
      std::uint64_t n[2];
      std::memcpy(n, counts[q].data() + 2 * g * sizeof(std::uint64_t), sizeof n);
      a.cell_at[g * counts.size() + q] = cells;
      a.corner_at[g * counts.size() + q] = corners;
      cells += n[0];
      corners += n[1];
    }
  for (const auto& c : counts) {
    std::uint64_t polygons = 0;
    std::memcpy(&polygons, c.data() + c.size() - sizeof polygons, sizeof polygons);
    a.polygons = a.polygons || polygons;
  }
  a.mesh.connectivity.resize(corners);
  if (a.polygons) a.corners.assign(cells, 0);
  for (const Field& f : w.mesh.cell_fields) {
    a.mesh.cell_fields.push_back(Field{f.name, f.components, {}});
    a.mesh.cell_fields.back().values.resize(static_cast<std::size_t>(f.components) * cells);
  }
}

// Rank 0: the polygons' offsets, and every point accounted for.
void finish(Assembly& a) {
  if (a.polygons) {
    a.mesh.offsets.resize(a.corners.size() + 1);
    a.mesh.offsets[0] = 0;
    for (std::size_t c = 0; c < a.corners.size(); ++c) a.mesh.offsets[c + 1] = a.mesh.offsets[c] + a.corners[c];
  }
  std::size_t missing = 0;
  for (std::uint8_t f : a.from) missing += f == 0;
  if (missing && a.error.empty())
    a.error = "gathered pieces: " + std::to_string(missing) + " points no piece holds (internal error)";
  if (!a.error.empty()) throw InputError(a.error);
}

}  // namespace

SurfaceMesh gather_pieces(const OwnPiece& piece, std::span<const std::uint32_t> own_group, std::uint32_t groups,
                          std::vector<std::uint64_t>* history_key) {
  const bool history = history_key != nullptr;
  const std::vector<std::vector<std::byte>> counts = gather_bytes(counts_bytes(piece, own_group, groups));
  Assembly a;
  const bool root = rank() == 0;
  if (root) {
    prepare(a, piece, counts, groups);
    if (history) {
      history_key->resize(a.from.size());
      a.history = history_key;
    }
  }
  const std::size_t record = point_record(piece.mesh, history);
  const std::vector<std::uint8_t> sent = sent_points(piece);
  std::size_t point = 0;
  gather_chunks([&](std::vector<std::byte>& chunk) { return points_chunk(piece, sent, history, point, chunk); },
                [&](int, const std::vector<std::byte>& chunk) { place_points(a, chunk, record); });
  Id cell = 0;
  gather_chunks([&](std::vector<std::byte>& chunk) { return cells_chunk(piece, own_group, cell, chunk); },
                [&](int q, const std::vector<std::byte>& chunk) { place_cells(a, q, chunk, groups); });
  if (!root) return {};
  finish(a);
  return std::move(a.mesh);
}

}  // namespace keymesh::distributed
