#pragma once
// The surface mesh and unstructured grid formats, one implementation file
// each (src/io/ply.cpp, obj.cpp, stl.cpp, vtp.cpp, gltf.cpp; vtu.cpp,
// legacy_vtk.cpp); the format table (src/io/formats.cpp) names them and
// mesh_io.hpp / grid_io.hpp dispatch through it. Private to io: the tests and
// fuzz targets reach them with src/ as an include directory.
// Every reader throws InputError naming the path on malformed input;
// `parse_*` parse bytes already in memory (`path` only names the source).
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::io {

// ---- what each format reads and writes ----

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


// Wavefront OBJ (geometry only).
// Write: `v x y z`, `vn` per point when a 3-component "Normals" field exists,
//        `f a b c` (or `f a//a b//b c//c` with normals), 1-based.
// Read:  `v` (extra w / colour values ignored), `f` with a, a/t, a//n and a/t/n
//        corners, negative (relative) indices. `vn` is read back as the
//        "Normals" field only when every face corner names a normal and each
//        point always gets the same one (as keymesh writes it); everything
//        else (vt, g, o, usemtl, l, p, ...) is ignored.

// STL (stereolithography).
// Write: binary; the facet normal is computed from each triangle (zero for a
//        degenerate one); polygons are fan-triangulated; point fields are lost.
// Read:  binary (recognised by its size, 84 + 50 n bytes, even when the
//        header starts with "solid") and ascii (one or more solids). STL has
//        no shared points: the reader welds corners whose positions are
//        exactly equal (float ==, -0 == +0), numbering the points in order
//        of first appearance. Facet normals are ignored.

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


// A ParaView parallel PolyData index (.pvtp) and its pieces (Source paths
// relative to the index). When every piece carries GlobalIds (as
// `mpirun ... keymesh contour -o X.pvtp` writes them) the pieces are welded
// by those ids, not by position: point g of the result is global point g,
// and copies must agree bit for bit. Otherwise the pieces are concatenated.

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

// VTK XML UnstructuredGrid (.vtu).
//
// Read: what VTK 9 and ParaView write: ascii, inline base64, appended raw or
//       base64; vtkZLibDataCompressor or none; UInt32/UInt64 headers; either
//       byte order; points of any float type (stored as float32); ids of any
//       integer type; several pieces (ids offset); point and cell data arrays
//       of any numeric type (stored as float).
// Write: binary appended raw, UInt64 header, Float32 points and fields,
//        Int32 or Int64 ids as the id width needs, UInt8 types; atomic.

// Legacy VTK files (.vtk), DATASET UNSTRUCTURED_GRID.
//
// Read: versions 2.0 to 5.1, ASCII and BINARY (big-endian): POINTS of any
//       numeric type, CELLS in the classic layout (a count before each
//       cell) or 5.x's OFFSETS / CONNECTIVITY, CELL_TYPES, POINT_DATA and
//       CELL_DATA with SCALARS (and LOOKUP_TABLE), VECTORS, NORMALS and
//       FIELD arrays; METADATA blocks are skipped. Any other dataset type is
//       refused by name.
// Write: version 4.2 BINARY (readable by VTK 5 to 9 and ParaView), float32
//        points and fields; ids must fit the format's 32-bit ints.

// ---- the functions the table (src/io/formats.cpp) and the tests call ----

// Whole files, opened through io::InputFile.
SurfaceMesh read_ply(const std::string& path);
SurfaceMesh read_obj(const std::string& path);
SurfaceMesh read_stl(const std::string& path);
SurfaceMesh read_vtp(const std::string& path);
SurfaceMesh read_pvtp(const std::string& path);
UnstructuredGrid read_vtu(const std::string& path);
UnstructuredGrid read_legacy_vtk(const std::string& path);

// Bytes already in memory (what the fuzz targets feed); `path` only names
// the source in errors.
SurfaceMesh parse_ply(std::string_view data, const std::string& path);
SurfaceMesh parse_obj(std::string_view data, const std::string& path);
SurfaceMesh parse_stl(std::string_view data, const std::string& path);
UnstructuredGrid parse_vtu(std::string_view data, const std::string& path);
UnstructuredGrid parse_legacy_vtk(std::string_view data, const std::string& path);
SurfaceMesh parse_vtp(std::string_view data, const std::string& path);
// With `global_ids`: an integer PointData array marked GlobalIds is returned
// there (one id per point, pieces concatenated; empty unless every piece
// with points has one) instead of becoming a float field. Every parse drops
// the cells marked DUPLICATECELL in a "vtkGhostType" array (ghost cells, a
// neighbouring piece's) and keeps no ghost array as a field; with
// `duplicate_points`, each point's DUPLICATEPOINT bit is returned there.
SurfaceMesh parse_vtp(std::string_view data, const std::string& path, std::vector<std::int64_t>* global_ids,
                      std::vector<std::uint8_t>* duplicate_points = nullptr);

// Atomic writes (temporary name, then rename). The pieces of a distributed
// mesh and their .pvtp index: io/mesh_io.hpp.
void write_ply(const SurfaceMesh& mesh, const std::string& path);
void write_obj(const SurfaceMesh& mesh, const std::string& path);
void write_stl(const SurfaceMesh& mesh, const std::string& path);
void write_vtp(const SurfaceMesh& mesh, const std::string& path);
void write_gltf_binary(const SurfaceMesh& mesh, const std::string& path);
void write_vtu(const UnstructuredGrid& grid, const std::string& path);
void write_legacy_vtk(const UnstructuredGrid& grid, const std::string& path);

// The DATASET type named in a legacy file's header ("UNSTRUCTURED_GRID",
// "POLYDATA", ...), or "" when the file is not a legacy VTK file.
std::string legacy_vtk_dataset(const std::string& path);

}  // namespace keymesh::io
