#pragma once
// Reading and writing surface meshes, dispatched on the extension. One file
// per format under io/.
//
// Write: .ply (binary little-endian, point fields as float properties;
//        polygons as a uchar/uint list), .obj (v, vn when a 3-component
//        "Normals" field exists, f), .stl (binary; triangles only, polygons
//        fan-triangulated), .vtp (VTK XML PolyData, binary appended raw data,
//        point fields as PointData arrays, "Normals" marked as normals).
// Read:  the same four formats (ascii and binary PLY, ascii and binary STL
//        with points welded by exact position, .vtp as written by keymesh,
//        VTK and ParaView: ascii, base64, appended raw, zlib or not), and
//        .pvtp indexes (pieces welded by their GlobalIds; see vtp.hpp).
#include <string>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::io {

SurfaceMesh read_mesh(const std::string& path);
void write_mesh(const SurfaceMesh& mesh, const std::string& path);

}  // namespace keymesh::io
