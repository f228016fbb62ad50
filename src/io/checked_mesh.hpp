#pragma once
// The one step every surface-mesh parser (.ply, .obj, .stl) ends with.
#include <string>

#include "keymesh/mesh/surface_mesh.hpp"
#include "mesh_bytes.hpp"

namespace keymesh::io {

// A parser's result is checked here (non-finite coordinates included), not
// only by read_mesh: every caller of a parser (the fuzz targets, Python's
// in-memory readers) relies on it.
inline SurfaceMesh checked_mesh(SurfaceMesh mesh, const std::string& path) {
  mesh_bytes::validate_mesh(mesh, path);
  return mesh;
}

}  // namespace keymesh::io
