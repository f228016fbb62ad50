#pragma once
// A rank's own piece of a mesh it made with halo rows (issue 36): a rank
// that makes the mesh of its rows plus a few rows of its neighbours on each
// side can smooth and coarsen it as one process does (what lies deep
// enough inside the halo has the one process's bits), then keep its share:
//  - its triangles: those made from its own rows (ghost_face 0);
//  - one layer of ghost cells: the halo's triangles that use a point of its
//    triangles (VTK's DUPLICATECELL), as the distributed contour's pieces;
//  - their points, numbered by the distributed KEY-REDUCE (number_keys). A
//    point belongs to the rank whose rows hold its row. The output's points
//    run segment after segment, in key order within one, and the row never
//    decreases along a segment's keys; so one all-gather of the first key
//    each rank owns per segment splits every segment by rank.
// Welded by their global ids, the pieces are the one-process mesh: its
// points in its order with the same bits, its triangles (piece by piece).
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "keymesh/distributed/key_exchange.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::distributed {

// order_key = segment << kSegmentShift | key within the segment.
constexpr int kSegmentShift = 47;

struct HaloMesh {
  const SurfaceMesh& mesh;                  // the rank's rows and halo, finished
  std::span<const std::uint8_t> ghost_face; // per triangle: 1 when a halo row made it
  std::span<const std::uint64_t> order_key; // per point, ascending
  std::span<const Id> row;                  // per point: the row that owns it
  int segments = 1;
  std::span<const std::uint64_t> history_key = {};  // per point, or empty: carried to OwnPiece's
};

struct OwnPiece {
  SurfaceMesh mesh;                         // own triangles, then the ghost cells
  std::vector<std::uint64_t> ids;           // global id of each point
  std::vector<std::uint64_t> history_key;   // each point's (HaloMesh::history_key), or empty
  std::vector<std::uint8_t> point_ghosts;   // 1 (DUPLICATEPOINT): another rank owns it
  std::vector<std::uint8_t> cell_ghosts;    // 1 (DUPLICATECELL): a ghost cell
  Id own_triangles = 0, points_owned = 0;
  long long total_points = 0;               // in the whole mesh
  std::uint64_t keys_requested = 0, bytes_sent = 0;
};

// Collective: this rank's piece; `rows` [first, end) are its own.
OwnPiece own_piece(const HaloMesh& halo, std::pair<Id, Id> rows);

}  // namespace keymesh::distributed
