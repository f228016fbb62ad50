// A rank's own piece of a mesh made with halo rows (keymesh/distributed/halo_piece.hpp).
// Built on number_keys and all_gather_bytes, so it compiles without MPI too
// (where number_keys refuses by name).
#include "keymesh/distributed/halo_piece.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/distributed/mpi.hpp"

namespace keymesh::distributed {

namespace {

bool owns(std::pair<Id, Id> rows, Id row) { return rows.first <= row && row < rows.second; }

// Which triangles and points this rank writes.
struct Share {
  std::vector<std::uint8_t> face;   // per triangle: 0 not written, 1 its own, 2 a ghost cell
  std::vector<std::uint8_t> point;  // per point: 1 when a written triangle uses it
  std::vector<std::uint8_t> held;   // per point: numbered here (written, or owned)
};

Share share_of(const HaloMesh& h, std::pair<Id, Id> rows) {
  const SurfaceMesh& m = h.mesh;
  const Id cells = m.num_cells(), n = m.num_points();
  Share s;
  s.face.assign(static_cast<std::size_t>(cells), 0);
  s.point.assign(static_cast<std::size_t>(n), 0);
  std::vector<std::uint8_t> mine(static_cast<std::size_t>(n), 0);  // used by an own triangle
  for (Id c = 0; c < cells; ++c) {
    if (h.ghost_face[static_cast<std::size_t>(c)]) continue;
    s.face[static_cast<std::size_t>(c)] = 1;
    for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k) mine[m.connectivity[k]] = 1;
  }
  for (Id c = 0; c < cells; ++c) {
    if (s.face[static_cast<std::size_t>(c)]) continue;
    bool touches = false;
    for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k) touches = touches || mine[m.connectivity[k]];
    if (touches) s.face[static_cast<std::size_t>(c)] = 2;
  }
  for (Id c = 0; c < cells; ++c)
    if (s.face[static_cast<std::size_t>(c)])
      for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k) s.point[m.connectivity[k]] = 1;
  s.held.resize(static_cast<std::size_t>(n));
  for (std::size_t p = 0; p < static_cast<std::size_t>(n); ++p) s.held[p] = s.point[p] || owns(rows, h.row[p]);
  return s;
}

// Collective: splits[s * (P + 1) + q], the first key of rank q in segment s.
// Rank q's points are those of its rows, and rows never decrease along a
// segment's keys, so the first key rank q (or a later rank) owns splits it.
std::vector<std::uint64_t> segment_splits(const HaloMesh& h, std::pair<Id, Id> rows) {
  const auto S = static_cast<std::size_t>(h.segments);
  std::vector<std::uint64_t> first(S, std::numeric_limits<std::uint64_t>::max());
  for (std::size_t p = 0; p < h.order_key.size(); ++p)
    if (owns(rows, h.row[p])) {
      const std::uint64_t k = h.order_key[p];
      first[k >> kSegmentShift] = std::min(first[k >> kSegmentShift], k);
    }
  std::vector<std::byte> mine(S * sizeof(std::uint64_t));
  if (S) std::memcpy(mine.data(), first.data(), mine.size());
  const auto all = all_gather_bytes(mine);
  const std::size_t P = all.size();
  std::vector<std::uint64_t> splits(S * (P + 1));
  for (std::size_t s = 0; s < S; ++s) {
    const std::uint64_t end = static_cast<std::uint64_t>(s + 1) << kSegmentShift;
    splits[s * (P + 1) + P] = end;
    for (std::size_t q = P; q-- > 0;) {
      std::uint64_t k = end;
      if (all[q].size() == mine.size()) std::memcpy(&k, all[q].data() + s * sizeof(std::uint64_t), sizeof k);
      splits[s * (P + 1) + q] = std::min(k, splits[s * (P + 1) + q + 1]);
    }
    splits[s * (P + 1)] = static_cast<std::uint64_t>(s) << kSegmentShift;
  }
  return splits;
}

// The written points (positions, fields, ids, marks), in the mesh's order.
std::vector<PointIndex> take_points(const HaloMesh& h, const Share& share, std::pair<Id, Id> rows,
                                    const GlobalNumbering& g, OwnPiece& w) {
  const SurfaceMesh& m = h.mesh;
  std::vector<PointIndex> local(share.point.size());
  std::size_t numbered = 0;  // index among the held points (number_keys' keys)
  for (std::size_t p = 0; p < share.point.size(); ++p) {
    if (!share.held[p]) continue;
    const std::size_t at = numbered++;
    if (!share.point[p]) continue;
    local[p] = static_cast<PointIndex>(w.ids.size());
    w.ids.push_back(g.ids[at]);
    if (!h.history_key.empty()) w.history_key.push_back(h.history_key[p]);
    w.mesh.points.insert(w.mesh.points.end(), m.points.begin() + 3 * p, m.points.begin() + 3 * p + 3);
    const bool owned = owns(rows, h.row[p]);
    w.point_ghosts.push_back(owned ? 0 : 1);
    w.points_owned += owned ? 1 : 0;
  }
  for (const Field& f : m.point_fields) {
    Field& to = w.mesh.point_fields.emplace_back(Field{f.name, f.components, {}});
    const auto k = static_cast<std::size_t>(f.components);
    for (std::size_t p = 0; p < share.point.size(); ++p)
      if (share.point[p]) to.values.insert(to.values.end(), f.values.begin() + k * p, f.values.begin() + k * (p + 1));
  }
  return local;
}

// The written triangles: its own first, then the ghost cells.
void take_cells(const SurfaceMesh& m, const Share& share, const std::vector<PointIndex>& local, OwnPiece& w) {
  const bool polygons = !m.all_triangles();
  if (polygons) w.mesh.offsets.push_back(0);
  for (const Field& f : m.cell_fields) w.mesh.cell_fields.push_back(Field{f.name, f.components, {}});
  for (const std::uint8_t kind : {std::uint8_t{1}, std::uint8_t{2}})
    for (Id c = 0; c < m.num_cells(); ++c) {
      if (share.face[static_cast<std::size_t>(c)] != kind) continue;
      for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k)
        w.mesh.connectivity.push_back(local[m.connectivity[k]]);
      if (polygons) w.mesh.offsets.push_back(w.mesh.connectivity.size());
      for (std::size_t i = 0; i < m.cell_fields.size(); ++i) {
        const Field& f = m.cell_fields[i];
        auto& to = w.mesh.cell_fields[i].values;
        to.insert(to.end(), f.values.begin() + f.components * c, f.values.begin() + f.components * (c + 1));
      }
      w.cell_ghosts.push_back(kind == 2 ? 1 : 0);
      w.own_triangles += kind == 1 ? 1 : 0;
    }
}

}  // namespace

OwnPiece own_piece(const HaloMesh& h, std::pair<Id, Id> rows) {
  if (h.ghost_face.size() != static_cast<std::size_t>(h.mesh.num_cells()) ||
      h.order_key.size() != static_cast<std::size_t>(h.mesh.num_points()) || h.row.size() != h.order_key.size() ||
      (!h.history_key.empty() && h.history_key.size() != h.order_key.size()))
    throw InputError("distributed pieces: marks for " + std::to_string(h.ghost_face.size()) + " triangles and " +
                     std::to_string(h.order_key.size()) + " points, not " + std::to_string(h.mesh.num_cells()) +
                     " and " + std::to_string(h.mesh.num_points()) + " (internal error)");
  const Share share = share_of(h, rows);
  std::vector<std::uint64_t> keys;
  for (std::size_t p = 0; p < share.held.size(); ++p)
    if (share.held[p]) keys.push_back(h.order_key[p]);
  const std::vector<std::uint64_t> splits = segment_splits(h, rows);
  const auto P = static_cast<std::size_t>(size());
  const GlobalNumbering g = number_keys(keys, h.segments, [&](int s, int q) {
    return splits[static_cast<std::size_t>(s) * (P + 1) + static_cast<std::size_t>(q)];
  });
  OwnPiece w;
  take_cells(h.mesh, share, take_points(h, share, rows, g, w), w);
  w.total_points = g.total;
  w.keys_requested = g.keys_requested;
  w.bytes_sent = g.bytes_sent;
  return w;
}

}  // namespace keymesh::distributed
