#include "keymesh/io/grid_io.hpp"

#include "keymesh/io/formats.hpp"
#include "mesh_formats.hpp"

namespace keymesh::io {

bool is_grid_file(const std::string& path) {
  const Format* format = format_by_name(path);
  const GridReader read = format ? function_of<GridReader>(*format) : nullptr;
  // A legacy .vtk may hold another dataset type (POLYDATA, ...).
  return read && (read != read_legacy_vtk || legacy_vtk_dataset(path) == "UNSTRUCTURED_GRID");
}

UnstructuredGrid read_grid(const std::string& path) { return function_for<GridReader>(path)(path); }

void write_grid(const UnstructuredGrid& grid, const std::string& path) { function_for<GridWriter>(path)(grid, path); }

}  // namespace keymesh::io
