#include "keymesh/io/mesh_io.hpp"

#include "keymesh/core/error.hpp"
#include "keymesh/io/formats.hpp"
#include "mesh_bytes.hpp"

namespace keymesh::io {

namespace {
[[noreturn]] void unknown_extension(const std::string& path) {
  throw InputError(path + ": unknown mesh file extension '" + file_extension(path) + "' (accepted: " +
                   accepted_surfaces() + ")");
}
}  // namespace

SurfaceMesh read_mesh(const std::string& path) {
  const Format* format = format_by_name(path);
  const SurfaceReader read = format ? reader_of<SurfaceReader>(*format) : nullptr;
  if (!read) unknown_extension(path);
  SurfaceMesh mesh = read(path);
  // What every operation relies on, non-finite coordinates included.
  mesh_bytes::validate_mesh(mesh, path);
  return mesh;
}

void write_mesh(const SurfaceMesh& mesh, const std::string& path) {
  const Format* format = format_by_name(path);
  const SurfaceWriter write = format ? writer_of<SurfaceWriter>(*format) : nullptr;
  if (!write) unknown_extension(path);
  write(mesh, path);
}

}  // namespace keymesh::io
