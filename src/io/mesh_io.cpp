#include "keymesh/io/mesh_io.hpp"

#include "keymesh/io/formats.hpp"
#include "mesh_bytes.hpp"

namespace keymesh::io {

SurfaceMesh read_mesh(const std::string& path) {
  SurfaceMesh mesh = function_for<SurfaceReader>(path)(path);
  // What every operation relies on, non-finite coordinates included.
  mesh_bytes::validate_mesh(mesh, path);
  return mesh;
}

void write_mesh(const SurfaceMesh& mesh, const std::string& path) { function_for<SurfaceWriter>(path)(mesh, path); }

}  // namespace keymesh::io
