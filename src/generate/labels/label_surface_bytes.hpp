#pragma once
// A slab's pieces of a label surface as bytes (internal to src/generate):
// how the ranks of `mpirun -np P keymesh labels` send theirs to rank 0.
// Native byte order and sizes: both ends are the same keymesh on one
// machine or one cluster of alike nodes.
#include <cstddef>
#include <vector>

#include "label_volume.hpp"

namespace keymesh::generate::detail {

// Appends the pieces (a list per slab, a piece per part) to `out`.
void write_pieces(const std::vector<std::vector<LabelSurface>>& pieces, std::vector<std::byte>& out);
// Reads what write_pieces wrote, appending the slabs to `pieces`; throws
// InputError when the bytes end early or hold more than they should.
void read_pieces(const std::vector<std::byte>& bytes, std::vector<std::vector<LabelSurface>>& pieces);

}  // namespace keymesh::generate::detail
