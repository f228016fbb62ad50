#pragma once
// STL (stereolithography).
// Write: binary; the facet normal is computed from each triangle (zero for a
//        degenerate one); polygons are fan-triangulated; point fields are lost.
// Read:  binary (recognised by its size, 84 + 50 n bytes, even when the
//        header starts with "solid") and ascii (one or more solids). STL has
//        no shared points: the reader welds corners whose positions are
//        exactly equal (float ==, -0 == +0), numbering the points in order
//        of first appearance. Facet normals are ignored.
#include <string>
#include <string_view>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::io {

SurfaceMesh read_stl(const std::string& path);
SurfaceMesh parse_stl(std::string_view data, const std::string& path);
void write_stl(const SurfaceMesh& mesh, const std::string& path);

}  // namespace keymesh::io
