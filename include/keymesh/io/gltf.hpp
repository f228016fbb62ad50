#pragma once
// glTF 2.0 binary (.glb), what web viewers (three.js, Babylon, model-viewer)
// and Blender load. Write only.
//
// One mesh of one triangle primitive (mode 4): POSITION (float VEC3, with the
// accessor min/max the specification requires), NORMAL when the mesh has a
// 3-component "Normals" field, every other point field of 1 to 4 components
// as an application-specific attribute "_<NAME>" (upper case, characters
// other than A-Z 0-9 as '_'), and uint32 indices. Polygons are
// fan-triangulated as for STL; cells of fewer than three points are dropped.
// Each array is its own tightly packed bufferView at a 4-byte aligned offset
// of the single BIN chunk; the JSON chunk is padded with spaces and the BIN
// chunk with zeros to 4 bytes. A mesh with no triangle is written as a scene
// with one empty node (glTF forbids empty accessors and buffers). Files past
// glTF's 32-bit length field (4 GiB) are refused (LimitError).
#include <string>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::io {

void write_gltf_binary(const SurfaceMesh& mesh, const std::string& path);

}  // namespace keymesh::io
