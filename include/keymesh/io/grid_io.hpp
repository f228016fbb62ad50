#pragma once
// Reading and writing unstructured grids, dispatched on the extension:
// .vtu (VTK XML, see vtu.hpp) and legacy .vtk (DATASET UNSTRUCTURED_GRID,
// see legacy_vtk.hpp).
#include <string>

#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::io {

// True for .vtu, and for a legacy .vtk whose header says UNSTRUCTURED_GRID.
bool is_grid_file(const std::string& path);

UnstructuredGrid read_grid(const std::string& path);
// Writes atomically (temporary name, then rename).
void write_grid(const UnstructuredGrid& grid, const std::string& path);

}  // namespace keymesh::io
