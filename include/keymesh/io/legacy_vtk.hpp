#pragma once
// Legacy VTK files (.vtk), DATASET UNSTRUCTURED_GRID.
//
// Read: versions 2.0 to 5.1, ASCII and BINARY (big-endian): POINTS of any
//       numeric type, CELLS in the classic layout (a count before each
//       cell) or 5.x's OFFSETS / CONNECTIVITY, CELL_TYPES, POINT_DATA and
//       CELL_DATA with SCALARS (and LOOKUP_TABLE), VECTORS, NORMALS and
//       FIELD arrays; METADATA blocks are skipped. Any other dataset type is
//       refused by name.
// Write: version 4.2 BINARY (readable by VTK 5 to 9 and ParaView), float32
//        points and fields; ids must fit the format's 32-bit ints.
#include <string>
#include <string_view>

#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::io {

UnstructuredGrid read_legacy_vtk(const std::string& path);
UnstructuredGrid parse_legacy_vtk(std::string_view data, const std::string& path);
void write_legacy_vtk(const UnstructuredGrid& grid, const std::string& path);
// The DATASET type named in a legacy file's header ("UNSTRUCTURED_GRID",
// "POLYDATA", ...), or "" when the file is not a legacy VTK file.
std::string legacy_vtk_dataset(const std::string& path);

}  // namespace keymesh::io
