#include "keymesh/io/grid_io.hpp"

#include "keymesh/core/error.hpp"
#include "keymesh/io/formats.hpp"
#include "mesh_formats.hpp"

namespace keymesh::io {

namespace {
[[noreturn]] void unknown_format(const std::string& path) {
  throw InputError(path + ": unknown unstructured grid format '" + file_extension(path) + "' (use " +
                   accepted_grids() + ")");
}
}  // namespace

bool is_grid_file(const std::string& path) {
  const Format* format = format_by_name(path);
  if (!format || !reader_of<GridReader>(*format)) return false;
  // A legacy .vtk may hold another dataset type (POLYDATA, ...).
  return reader_of<GridReader>(*format) != read_legacy_vtk || legacy_vtk_dataset(path) == "UNSTRUCTURED_GRID";
}

UnstructuredGrid read_grid(const std::string& path) {
  const Format* format = format_by_name(path);
  const GridReader read = format ? reader_of<GridReader>(*format) : nullptr;
  if (!read) unknown_format(path);
  return read(path);
}

void write_grid(const UnstructuredGrid& grid, const std::string& path) {
  const Format* format = format_by_name(path);
  const GridWriter write = format ? writer_of<GridWriter>(*format) : nullptr;
  if (!write) unknown_format(path);
  write(grid, path);
}

}  // namespace keymesh::io
