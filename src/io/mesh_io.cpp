#include "keymesh/io/mesh_io.hpp"

#include "keymesh/core/error.hpp"
#include "keymesh/io/gltf.hpp"
#include "keymesh/io/mesh_bytes.hpp"
#include "keymesh/io/obj.hpp"
#include "keymesh/io/ply.hpp"
#include "keymesh/io/stl.hpp"
#include "keymesh/io/vtp.hpp"

namespace keymesh::io {

namespace {
constexpr const char* kAccepted = ".ply, .obj, .stl, .vtp; .pvtp to read; .glb to write";

[[noreturn]] void unknown_extension(const std::string& path, const std::string& ext) {
  throw InputError(path + ": unknown mesh file extension '" + ext + "' (accepted: " + kAccepted + ")");
}
}  // namespace

namespace {
SurfaceMesh read_by_extension(const std::string& path) {
  const std::string ext = mesh_bytes::lower_extension(path);
  if (ext == ".ply") return read_ply(path);
  if (ext == ".obj") return read_obj(path);
  if (ext == ".stl") return read_stl(path);
  if (ext == ".vtp") return read_vtp(path);
  if (ext == ".pvtp") return read_pvtp(path);
  unknown_extension(path, ext);
}
}  // namespace

SurfaceMesh read_mesh(const std::string& path) {
  SurfaceMesh mesh = read_by_extension(path);
  // What every operation relies on, non-finite coordinates included.
  mesh_bytes::validate_mesh(mesh, path);
  return mesh;
}

void write_mesh(const SurfaceMesh& mesh, const std::string& path) {
  const std::string ext = mesh_bytes::lower_extension(path);
  if (ext == ".ply") return write_ply(mesh, path);
  if (ext == ".obj") return write_obj(mesh, path);
  if (ext == ".stl") return write_stl(mesh, path);
  if (ext == ".vtp") return write_vtp(mesh, path);
  if (ext == ".glb") return write_gltf_binary(mesh, path);
  unknown_extension(path, ext);
}

}  // namespace keymesh::io
