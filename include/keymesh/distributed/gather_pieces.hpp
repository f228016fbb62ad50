#pragma once
// A mesh made in pieces (halo_piece.hpp's OwnPiece: each rank its own
// triangles and the points they use, with their global ids) put together on
// rank 0 as one mesh: the gathered output of `mpirun -np P keymesh contour
// --coarsen -o OUT.vtp` (issue 36). Every rank coarsens its own layers with
// a halo, as for .pvtp pieces, and only the coarse pieces travel: rank 0
// never holds the fine mesh of more than its own layers.
//
// The pieces, welded by their global ids, are the one process's mesh (its
// points in its order with the same bits, its triangles); what the pieces
// lose is the triangles' order across ranks, which the caller gives back as
// a group per own triangle: the one process writes its triangles group by
// group (an isovalue each), and within a group layer after layer, so rank
// after rank.
#include <cstdint>
#include <span>
#include <vector>

#include "keymesh/distributed/halo_piece.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::distributed {

// Collective: on rank 0 the whole mesh (point i: global id i, taken from its
// owner's copy where it sends one, every copy being the same bits; cells
// group by group, rank by rank within a group, each rank's own triangles in
// its order, with their cell fields), on the others an empty mesh.
// `own_group[t]` is own triangle t's group, below `groups`. Each rank's
// points, then its cells, reach rank 0 one rank after another in chunks of
// 2^16 (gather_chunks): besides its piece a rank holds one chunk, and rank 0
// the whole mesh.
// `history_key` (given on every rank or none): rank 0 receives every
// point's history key (OwnPiece::history_key, which every rank then holds).
// Throws (on rank 0, after every rank's share arrived) InputError when a
// global id is missing or out of range, or a group too large.
SurfaceMesh gather_pieces(const OwnPiece& piece, std::span<const std::uint32_t> own_group, std::uint32_t groups,
                          std::vector<std::uint64_t>* history_key = nullptr);

}  // namespace keymesh::distributed
