#pragma once
// Distributed contouring over MPI: `mpirun -np P keymesh contour`.
//
// Each rank reads only its slab of the volume (its voxel layers plus the
// plane above them: the one sample layer a cell needs), contours it with
// global edge keys (3 * point id of the whole grid + axis, isovalue-major),
// and number_keys (key_exchange.hpp) gives every point one global id: a
// point belongs to the rank whose slab starts at its plane, so the only keys
// two ranks share are those of the plane between them, and they are welded
// by key, not by position. The result is either one piece per rank (its
// points with their global ids, written as a .vtp piece of a .pvtp) or the
// whole mesh gathered on rank 0, byte-identical to the single-process run.
#include <vector>

#include "keymesh/distributed/key_exchange.hpp"
#include "keymesh/generate/contour/contour_stream.hpp"
#include "keymesh/generate/contour/layer_blocks.hpp"

namespace keymesh::distributed {

// What one rank did, for the report and docs/SCALING.md.
struct RankStats {
  double first_plane = 0, planes = 0;        // its slab
  double slabs = 0;                          // the parts it was read in (more than 1 under --memory-limit)
  double points = 0, points_owned = 0, triangles = 0;
  // Points of the largest fine mesh it held: its slab's, or on rank 0 of a
  // gathered output the whole mesh (set by the command after gather()).
  double fine_points_held = 0;
  double keys_requested = 0, bytes_sent = 0; // in the key exchange
  // Seconds: reading the slab, balancing (counting its layers' triangles and
  // agreeing on new boundaries, with balance), contouring it, waiting for the slowest rank
  // (load imbalance), the key exchange itself, writing or gathering.
  double read = 0, balance = 0, contour = 0, wait = 0, exchange = 0, output = 0;
};

struct ContourPiece {
  SurfaceMesh mesh;             // this rank's triangles, local point ids
  GlobalNumbering numbering;    // global id of each local point
  std::vector<std::uint64_t> keys;
  RankStats stats;
  // Averaged normals of a gathered mesh: rank 0 sums them again over the
  // whole in one process's blocks of layers (generate/layer_blocks.hpp), so
  // the file is that process's bit for bit; a piece keeps its owners' merge.
  bool average = false;
  generate::LayerGrid layer_grid;
};

// Throws InputError naming what a distributed contour of this volume with
// these options on `ranks` ranks cannot do (not collective: every rank
// reaches the same verdict, so the CLI refuses without MPI_Abort).
void require_distributable(const ImageGrid& header, const generate::ContourOptions& options, int ranks);

// Collective: every rank calls it with its own source of the same volume.
// Supports scalars, several isovalues, --weld keyreduce, --normals gradient
// and --curvature (ghost planes), --normals average (partial sums merged at
// the owner; gather() sums the whole again in one process's order);
// VERTEX-WELD and the GPU are refused by name. Not coarsening: that is
// coarse_piece's (coarse_pieces.hpp), whose pieces gather_pieces gathers.
// With `balance`, the slab boundaries move so that every rank gets about the
// same work (triangles per layer counted on the equal split first, then
// shared); without, every rank gets the same number of voxel layers. The
// output is the same either way. With `memory_limit` (bytes of samples
// held at once, not with balance), the rank streams its planes in slabs
// (generate::contour_planes_streamed): the same piece.
ContourPiece contour_piece(PlaneSource& source, const generate::ContourOptions& options, bool balance,
                           std::size_t memory_limit = 0);

// Collective: the voxel layers of every rank, rank q's [bounds[q],
// bounds[q + 1]): equal counts, or balanced as contour_piece balances them.
std::vector<Id> slab_bounds(PlaneSource& source, const generate::ContourOptions& options, bool balance);

// The fine surface of voxel layers [first, end) with every point's global
// edge key and nearest grid point (its coarse key), read from `source` (a
// ghost plane either side for derivatives, as contour_piece reads them);
// averaged normals are left to the caller. Not collective. A non-zero
// `memory_limit` (--memory-limit) streams the planes in slabs of at most
// that many bytes, merged by key: the same mesh, keys and nearest grid
// points as one read (generate::contour_planes_streamed).
struct FineLayers {
  SurfaceMesh mesh;
  std::vector<std::uint64_t> keys, nearest;
  double read = 0, contour = 0;  // seconds
  Id slabs = 1;                  // reads made
};
FineLayers contour_layers(PlaneSource& source, const generate::ContourOptions& options, Id first, Id end,
                          std::size_t memory_limit = 0);

// Collective: rank 0 returns the whole mesh (points in global id order,
// triangles isovalue by isovalue in rank order: the single-process file),
// the others an empty one. Adds the gather's time to piece.stats.output.
// point_keys (given on every rank or none): rank 0 receives the whole
// mesh's points' edge keys (history_key), in its point order.
SurfaceMesh gather(ContourPiece& piece, std::vector<std::uint64_t>* point_keys = nullptr);

// A rank's piece as VTK's parallel pipeline wants it: its triangles, then
// one layer of ghost cells (the neighbouring ranks' triangles that use a
// point this rank holds, so that per-piece filters see across the shared
// planes) with the points they add; every point's global id; VTK's
// vtkGhostType marks: point_ghosts 1 (DUPLICATEPOINT) on the points another
// rank owns, cell_ghosts 1 (DUPLICATECELL) on the ghost cells.
struct GhostedPiece {
  SurfaceMesh mesh;
  std::vector<std::uint64_t> ids;
  std::vector<std::uint64_t> keys;  // every point's edge key (history_key)
  std::vector<std::uint8_t> point_ghosts, cell_ghosts;
};

// Collective: each rank sends its neighbours (the only ranks that hold its
// points: the planes it shares with them) the triangles touching those
// planes, with their points' ids, keys, positions and fields; it keeps what it
// receives that uses a point it holds. Moves the piece's mesh, ids and keys into
// the result.
GhostedPiece ghosted_piece(ContourPiece& piece);

// Collective: every rank's stats, on rank 0 (empty elsewhere).
std::vector<RankStats> gather_stats(const RankStats& mine);

}  // namespace keymesh::distributed
