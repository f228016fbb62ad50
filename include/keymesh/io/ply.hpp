#pragma once
// Stanford PLY.
// Write: binary_little_endian 1.0; `element vertex` with float x y z and one
//        float property per point-field component (the field's name for one
//        component, name_0, name_1, ... otherwise; a 3-component "Normals"
//        field as nx ny nz); `element face` with `property list uchar uint
//        vertex_indices` (uint count when a polygon has more than 255 points).
// Read:  ascii, binary_little_endian, binary_big_endian. Vertex x y z of any
//        numeric type; nx ny nz become the "Normals" field; runs of scalar
//        properties named p_0, p_1, ... p_k become one k+1 component field "p";
//        every other scalar vertex property becomes a 1-component field. The
//        face list `vertex_indices` (or `vertex_index`) with any integer count
//        and index types; polygons of any size (offsets set unless all are
//        triangles). Unknown elements and properties are skipped.
#include <string>
#include <string_view>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::io {

SurfaceMesh read_ply(const std::string& path);
// Parses PLY bytes already in memory; `path` only names the source in errors.
SurfaceMesh parse_ply(std::string_view data, const std::string& path);
void write_ply(const SurfaceMesh& mesh, const std::string& path);

}  // namespace keymesh::io
