#pragma once
// The files of a mesh written in pieces under `mpirun -np P keymesh ... -o
// OUT.pvtp`: every rank its piece OUT_<rank>.vtp (its points' global ids,
// VTK's ghost marks), rank 0 the index OUT.pvtp once every piece exists.
#include <string>
#include <vector>

#include "keymesh/io/mesh_io.hpp"

namespace keymesh::cli {

// Collective: writes this rank's piece, then (rank 0) the index. Any rank's
// failure is every rank's (distributed::SharedError, said once by rank 0):
// no index is written and this rank's piece is removed. `uint64_arrays`:
// UInt64 point arrays of the piece (write_vtp's), declared by the index too.
void write_piece_files(const SurfaceMesh& piece, const std::vector<std::uint64_t>& global_ids,
                       const io::PieceGhosts& ghosts, const std::string& output,
                       const std::vector<io::UInt64PointArray>& uint64_arrays = {});

}  // namespace keymesh::cli
