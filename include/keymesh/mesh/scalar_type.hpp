#pragma once
// ScalarType: the one list of sample types keymesh knows, with their names
// and sizes. Files name the whole list (PLY, VTK and legacy VTK arrays of
// 32- and 64-bit integers); an ImageGrid holds the first seven
// (is_grid_scalar), the ones every algorithm is instantiated for by
// visit_scalars.
#include <cstddef>
#include <cstdint>
#include <string>

namespace keymesh {

// The grid types first, in their historical order; the file-only types after.
enum class ScalarType : std::uint8_t {
  UInt8, Int8, UInt16, Int16, Int32, Float32, Float64,  // grid and file types
  UInt32, Int64, UInt64                                 // file types only
};

// Size in bytes of one sample (inline: readers ask it per value).
constexpr std::size_t scalar_size(ScalarType type) {
  switch (type) {
    case ScalarType::UInt8:
    case ScalarType::Int8: return 1;
    case ScalarType::UInt16:
    case ScalarType::Int16: return 2;
    case ScalarType::Int32:
    case ScalarType::UInt32:
    case ScalarType::Float32: return 4;
    case ScalarType::Float64:
    case ScalarType::Int64:
    case ScalarType::UInt64: return 8;
  }
  return 0;
}
// "uint8", "int8", "uint16", "int16", "int32", "float32", "float64",
// "uint32", "int64", "uint64".
const char* scalar_type_name(ScalarType type);
bool scalar_is_float(ScalarType type);
// True for the types an ImageGrid may hold.
bool is_grid_scalar(ScalarType type);
// Parses a grid type's name above and common aliases ("uchar", "float",
// "double", ...); throws InputError naming the text when unknown.
ScalarType parse_scalar_type(const std::string& text);

}  // namespace keymesh
