#include "keymesh/io/grid_io.hpp"

#include "keymesh/core/error.hpp"
#include "keymesh/io/legacy_vtk.hpp"
#include "keymesh/io/mesh_bytes.hpp"
#include "keymesh/io/vtu.hpp"

namespace keymesh::io {

bool is_grid_file(const std::string& path) {
  const std::string ext = mesh_bytes::lower_extension(path);
  if (ext == ".vtu") return true;
  return ext == ".vtk" && legacy_vtk_dataset(path) == "UNSTRUCTURED_GRID";
}

UnstructuredGrid read_grid(const std::string& path) {
  const std::string ext = mesh_bytes::lower_extension(path);
  if (ext == ".vtu") return read_vtu(path);
  if (ext == ".vtk") return read_legacy_vtk(path);
  throw InputError(path + ": unknown unstructured grid format '" + ext + "' (use .vtu or .vtk)");
}

void write_grid(const UnstructuredGrid& grid, const std::string& path) {
  const std::string ext = mesh_bytes::lower_extension(path);
  if (ext == ".vtu") return write_vtu(grid, path);
  if (ext == ".vtk") return write_legacy_vtk(grid, path);
  throw InputError(path + ": unknown unstructured grid format '" + ext + "' (use .vtu or .vtk)");
}

}  // namespace keymesh::io
