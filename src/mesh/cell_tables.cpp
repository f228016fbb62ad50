#include "keymesh/mesh/cell_tables.hpp"

#include "keymesh/core/error.hpp"

namespace keymesh::cells {

std::vector<std::array<std::uint64_t, 8>> hex_corners(const UnstructuredGrid& hexes, const std::string& who) {
  const Id cells = hexes.num_cells();
  std::vector<std::array<std::uint64_t, 8>> corner(static_cast<std::size_t>(cells));
  for (Id c = 0; c < cells; ++c) {
    const std::uint8_t t = hexes.cell_type(c);
    if (t != std::uint8_t(CellType::Hexahedron) && t != std::uint8_t(CellType::Voxel))
      throw InputError(who + ": cell " + std::to_string(c) + " is a " + cell_type_name(t) + ", not a hexahedron");
    const std::uint64_t b = hexes.cell_begin(c);
    for (int h = 0; h < 8; ++h)
      corner[c][t == std::uint8_t(CellType::Voxel) ? h : kHexToBits[h]] = hexes.connectivity[b + h];
  }
  return corner;
}

}  // namespace keymesh::cells
