#include "keymesh/mesh/scalar_type.hpp"

#include <algorithm>
#include <cctype>

#include "keymesh/core/error.hpp"

namespace keymesh {

const char* scalar_type_name(ScalarType type) {
  switch (type) {
    case ScalarType::UInt8: return "uint8";
    case ScalarType::Int8: return "int8";
    case ScalarType::UInt16: return "uint16";
    case ScalarType::Int16: return "int16";
    case ScalarType::Int32: return "int32";
    case ScalarType::Float32: return "float32";
    case ScalarType::Float64: return "float64";
    case ScalarType::UInt32: return "uint32";
    case ScalarType::Int64: return "int64";
    case ScalarType::UInt64: return "uint64";
  }
  return "unknown";
}

bool scalar_is_float(ScalarType type) { return type == ScalarType::Float32 || type == ScalarType::Float64; }

bool is_grid_scalar(ScalarType type) {
  return type != ScalarType::UInt32 && type != ScalarType::Int64 && type != ScalarType::UInt64;
}

bool is_label_scalar(ScalarType type) { return !scalar_is_float(type); }

ScalarType parse_scalar_type(const std::string& raw) {
  std::string t = raw;
  std::transform(t.begin(), t.end(), t.begin(), [](unsigned char c) { return std::tolower(c); });
  if (t == "uint8" || t == "uchar" || t == "unsigned char" || t == "u8") return ScalarType::UInt8;
  if (t == "int8" || t == "char" || t == "signed char" || t == "i8") return ScalarType::Int8;
  if (t == "uint16" || t == "ushort" || t == "unsigned short" || t == "u16") return ScalarType::UInt16;
  if (t == "int16" || t == "short" || t == "i16") return ScalarType::Int16;
  if (t == "int32" || t == "int" || t == "i32") return ScalarType::Int32;
  if (t == "uint32" || t == "uint" || t == "unsigned int" || t == "u32") return ScalarType::UInt32;
  if (t == "int64" || t == "i64") return ScalarType::Int64;
  if (t == "uint64" || t == "u64") return ScalarType::UInt64;
  if (t == "float32" || t == "float" || t == "f32") return ScalarType::Float32;
  if (t == "float64" || t == "double" || t == "f64") return ScalarType::Float64;
  throw InputError("unknown scalar type '" + raw +
                   "' (expected uint8, int8, uint16, int16, int32, uint32, int64, uint64, float32 or float64)");
}

}  // namespace keymesh
