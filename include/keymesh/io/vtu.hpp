#pragma once
// VTK XML UnstructuredGrid (.vtu).
//
// Read: what VTK 9 and ParaView write: ascii, inline base64, appended raw or
//       base64; vtkZLibDataCompressor or none; UInt32/UInt64 headers; either
//       byte order; points of any float type (stored as float32); ids of any
//       integer type; several pieces (ids offset); point and cell data arrays
//       of any numeric type (stored as float).
// Write: binary appended raw, UInt64 header, Float32 points and fields,
//        Int32 or Int64 ids as the id width needs, UInt8 types; atomic.
#include <string>
#include <string_view>

#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::io {

UnstructuredGrid read_vtu(const std::string& path);
UnstructuredGrid parse_vtu(std::string_view data, const std::string& path);
void write_vtu(const UnstructuredGrid& grid, const std::string& path);

}  // namespace keymesh::io
