#pragma once
// Wavefront OBJ (geometry only).
// Write: `v x y z`, `vn` per point when a 3-component "Normals" field exists,
//        `f a b c` (or `f a//a b//b c//c` with normals), 1-based.
// Read:  `v` (extra w / colour values ignored), `f` with a, a/t, a//n and a/t/n
//        corners, negative (relative) indices. `vn` is read back as the
//        "Normals" field only when every face corner names a normal and each
//        point always gets the same one (as keymesh writes it); everything
//        else (vt, g, o, usemtl, l, p, ...) is ignored.
#include <string>
#include <string_view>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::io {

SurfaceMesh read_obj(const std::string& path);
SurfaceMesh parse_obj(std::string_view data, const std::string& path);
void write_obj(const SurfaceMesh& mesh, const std::string& path);

}  // namespace keymesh::io
