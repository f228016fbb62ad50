#pragma once
// The one writer of VTK XML files with raw appended data (.vtp, .vtu, .vti):
// version 1.0, LittleEndian, header_type UInt64, every array
// format="appended" in one <AppendedData encoding="raw"> section, each block
// its byte count (UInt64) then its values. The XML comes first in the file,
// so an array's offset must be known when it is declared: declaring an array
// returns its <DataArray .../> line and queues its block, and write() emits
// the blocks in the order they were declared. Arrays already in the file's
// layout are written from memory as they are; the others are converted a
// chunk at a time, never into one copy of the whole array.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "keymesh/mesh/scalar_type.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::io::vtk_xml {

// `<?xml version="1.0"?>` and the opening <VTKFile> line of a file of `type`
// ("PolyData", "PPolyData", "UnstructuredGrid", "ImageData").
std::string file_header(std::string_view type);

// The attributes a <PointData>/<CellData> gives its fields: the first
// 1-component field as Scalars, a 3-component "Normals" as Normals.
std::string field_attributes(const std::vector<Field>& fields);

class AppendedArrays {
 public:
  // Each declares one array and returns its <DataArray .../> line (indented
  // for a section of a <Piece>); `components` 0 leaves NumberOfComponents out.
  // The data must stay alive and unchanged until write().
  std::string floats(std::string_view name, int components, const keymesh::Array<float>& values);
  // Values of `type` stored in memory as the file wants them (native order).
  std::string bytes(ScalarType type, std::string_view name, int components, const void* data, std::uint64_t size);
  // `count` integers of `type` (Int32, Int64 or UInt8): value_at(i) for each i.
  template <class ValueAt>
  std::string integers(ScalarType type, std::string_view name, std::uint64_t count, ValueAt value_at) {
    return integer_chunks(type, name, count, [value_at](std::uint64_t first, std::size_t n, std::int64_t* out) {
      for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::int64_t>(value_at(first + i));
    });
  }

  // Writes `xml` (the file up to its last declared array's section),
  // the appended blocks and the closing tags to path, atomically.
  void write(const std::string& path, std::string_view xml) const;

 private:
  // Fills out[0, n) with the values first, first + 1, ...
  using ChunkFill = std::function<void(std::uint64_t first, std::size_t n, std::int64_t* out)>;
  struct Block {
    ScalarType type;
    std::uint64_t count;       // values
    const void* data;          // stored as the file wants them, or null: fill
    ChunkFill fill;
  };
  std::string integer_chunks(ScalarType type, std::string_view name, std::uint64_t count, ChunkFill fill);
  std::string declare(Block block, std::string_view name, int components);

  std::vector<Block> blocks_;
  std::uint64_t offset_ = 0;  // where the next block starts in the appended section
};

}  // namespace keymesh::io::vtk_xml
