#pragma once
// The coarsened contour in pieces under `mpirun -np P` (issue 36,
// docs/decisions/contour-coarsen-pieces.md): every rank contours its voxel
// layers plus `h` halo layers on each side, coarsens them with the one
// process's code (generate/coarsen/coarsen.hpp, coarsen_part: the
// non-manifold split's rounds agreed by all ranks), and keeps its share
// (halo_piece.hpp): the coarse triangles its own layers made, one layer of
// ghost cells, and their points numbered by the distributed KEY-REDUCE.
// Nothing is gathered.
//
// Positions, folds and fans of a coarse point read only the voxel layers
// touching it, but the split's decisions reach along chains of points that
// are not one closed fan (a plate one voxel thick makes one as long as the
// plate). So each rank checks that no such chain reaching a point it writes
// or owns touches the two outer planes of its halo, where its mesh is cut;
// if any rank's does, all grow the halo (doubling) and start again, up to
// the whole volume. The pieces, welded by their global ids, are then the
// one process's output: its points in its order with the same bits
// (averaged normals included), its triangles.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "keymesh/distributed/halo_piece.hpp"
#include "keymesh/generate/contour/contour_stream.hpp"

namespace keymesh::distributed {

struct CoarsePiece {
  OwnPiece piece;               // own triangles, then the ghost cells
  std::vector<std::uint32_t> own_isovalue;  // per own triangle: its isovalue's index (gather_pieces' group)
  Id first_layer = 0, layers = 0;
  Id halo_layers = 0;           // the halo that passed the check
  int attempts = 0;             // halos tried (1: the first passed)
  Id slabs = 0;                 // reads of planes, all attempts (one each without --memory-limit)
  Id fine_points_held = 0;      // the most fine points held at once: its layers and halo, largest attempt
  Id triangles_before = 0;      // fine triangles of its own layers
  // check_fans' counts at the points it owns (their share of the whole's).
  Id nonmanifold_edges = 0, nonmanifold_vertices = 0, boundary_edges = 0;
  double read = 0, contour = 0, coarsen = 0, number = 0;  // seconds, all attempts
};

// The halo first tried, in voxel layers.
constexpr Id kFirstCoarseHalo = 8;

// Collective: this rank's piece of the coarsened contour. A non-zero
// `memory_limit` (--memory-limit, bytes of samples) reads every attempt's
// planes in slabs within it and merges them by key into the fine mesh one
// read gives (contour_layers), so the pieces are those made without it.
CoarsePiece coarse_piece(PlaneSource& source, const generate::ContourOptions& options, bool balance,
                         std::size_t memory_limit = 0);

}  // namespace keymesh::distributed
