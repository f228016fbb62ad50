#pragma once
// Corner, edge and face tables of the linear cells, in one place.
//
// Hexahedra are handled in bit order: corner c sits at
// (c & 1, (c >> 1) & 1, (c >> 2) & 1) of the unit cube (VTK_VOXEL's order).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "keymesh/core/device.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::cells {

// VTK_HEXAHEDRON lists the bottom face counter-clockwise, then the top face:
// its corner h is bit corner kHexToBits[h].
inline constexpr int kHexToBits[8] = {0, 1, 3, 2, 4, 5, 7, 6};

// The six faces of a hexahedron, -x, +x, -y, +y, -z, +z, each as the cycle
// of its bit corners around the face.
inline constexpr int kHexFaceCycle[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                            {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};

// The six edges of a tetrahedron (corners 0..3).
inline constexpr int kTetEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

// kTetEdges[e][end] for the device paths: a GPU kernel cannot read a host
// array, so the table is packed into one constant (a nibble per corner,
// edge e in byte e), checked against kTetEdges below.
KEYMESH_HD constexpr int tet_edge_corner(int e, int end) {
  return static_cast<int>((std::uint64_t{0x323121302010} >> (8 * e + 4 * end)) & 0xF);
}
static_assert([] {
  for (int e = 0; e < 6; ++e)
    if (tet_edge_corner(e, 0) != kTetEdges[e][0] || tet_edge_corner(e, 1) != kTetEdges[e][1]) return false;
  return true;
}());

// The corner ids of every cell of a grid of hexahedra (VTK_HEXAHEDRON or
// VTK_VOXEL), in bit order; InputError naming `who` and the cell for any
// other cell type.
std::vector<std::array<std::uint64_t, 8>> hex_corners(const UnstructuredGrid& hexes, const std::string& who);

}  // namespace keymesh::cells
