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
#include <vector>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::io {

SurfaceMesh read_mesh(const std::string& path);
void write_mesh(const SurfaceMesh& mesh, const std::string& path);

// A piece of a distributed mesh (`mpirun ... keymesh contour -o X.pvtp`):
// a .vtp with an Int64 PointData array "GlobalPointIds" marked GlobalIds,
// its points' ids in the whole mesh.
// With `ghosts`, VTK's ghost marks as UInt8 "vtkGhostType" arrays, one per
// point and one per cell (vtkDataSetAttributes::DUPLICATEPOINT = 1 on the
// points another piece owns, DUPLICATECELL = 1 on the cells a piece carries
// for its neighbours): what keymesh's reader drops and VTK's filters skip.
struct PieceGhosts {
  std::vector<std::uint8_t> points, cells;
};
// `uint64_arrays`: UInt64 PointData arrays written after the float point
// fields, one value per point each (a contour's history_key: the mesh's own
// fields are floats). keymesh's readers read them back as float fields.
struct UInt64PointArray {
  std::string name;
  const std::vector<std::uint64_t>* values = nullptr;
};
void write_vtp(const SurfaceMesh& mesh, const std::string& path, const std::vector<std::uint64_t>* global_point_ids,
               const PieceGhosts* ghosts = nullptr, const std::vector<UInt64PointArray>& uint64_arrays = {});

// A ParaView parallel PolyData index (.pvtp) over piece files written by
// write_vtp (Source paths relative to the index); `like` gives the point
// fields every piece has.
void write_pvtp(const std::string& path, const SurfaceMesh& like, const std::vector<std::string>& pieces,
                bool global_point_ids);
// Pieces written with ghosts: GhostLevel 1 and the vtkGhostType arrays
// declared; `uint64_arrays` names the pieces' UInt64 point arrays (write_vtp's).
void write_pvtp(const std::string& path, const SurfaceMesh& like, const std::vector<std::string>& pieces,
                bool global_point_ids, bool ghosts, const std::vector<std::string>& uint64_arrays = {});

}  // namespace keymesh::io
