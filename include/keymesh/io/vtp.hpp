#pragma once
// VTK XML PolyData (.vtp).
// Write: version 1.0, header_type UInt64, LittleEndian, no compression,
//        <AppendedData encoding="raw">; Points Float32; Polys connectivity and
//        offsets Int64; each point field as a Float32 PointData array with its
//        NumberOfComponents; "Normals" (3 components) marked Normals="Normals",
//        the first 1-component field marked as Scalars.
// Read:  files written by keymesh, VTK and ParaView: DataArray format ascii,
//        binary (base64 inline) and appended (raw or base64), with or without
//        vtkZLibDataCompressor, UInt32 or UInt64 headers, either byte order;
//        Points Float32/Float64 (any numeric type); Polys connectivity and
//        offsets of any integer type; triangle Strips are split into
//        triangles; Verts and Lines are ignored; every numeric PointData
//        array becomes a float field (the array marked as Normals
//        is renamed "Normals"); several Pieces are concatenated, keeping
//        the fields every piece has.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::io {

SurfaceMesh read_vtp(const std::string& path);
SurfaceMesh parse_vtp(std::string_view data, const std::string& path);
// With `global_ids`: an integer PointData array marked GlobalIds is returned
// there (one id per point, pieces concatenated; empty unless every piece
// with points has one) instead of becoming a float field.
SurfaceMesh parse_vtp(std::string_view data, const std::string& path, std::vector<std::int64_t>* global_ids);

// A ParaView parallel PolyData index (.pvtp) and its pieces (Source paths
// relative to the index). When every piece carries GlobalIds (as
// `mpirun ... keymesh contour -o X.pvtp` writes them) the pieces are welded
// by those ids, not by position: point g of the result is global point g,
// and copies must agree bit for bit. Otherwise the pieces are concatenated.
SurfaceMesh read_pvtp(const std::string& path);
void write_vtp(const SurfaceMesh& mesh, const std::string& path);
// With an Int64 PointData array "GlobalPointIds" marked GlobalIds (a piece
// of a distributed mesh: its points' ids in the whole mesh).
void write_vtp(const SurfaceMesh& mesh, const std::string& path, const std::vector<std::uint64_t>* global_point_ids);

// A ParaView parallel PolyData index (.pvtp) over piece files written by
// write_vtp (Source paths relative to the index); `like` gives the point
// fields every piece has.
void write_pvtp(const std::string& path, const SurfaceMesh& like, const std::vector<std::string>& pieces,
                bool global_point_ids);

}  // namespace keymesh::io
