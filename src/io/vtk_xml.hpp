#pragma once
// The parts of VTK's XML file formats (.vtp, .vti, .vtu) every reader shares:
// a minimal XML parser and the DataArray decoder (ascii, base64 binary,
// appended raw or base64; vtkZLibDataCompressor; UInt32/UInt64 headers;
// either byte order), with every size checked against the bytes present.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "mesh_bytes.hpp"

namespace keymesh::io::vtk_xml {

// An element. Children are owned; the destructor frees a subtree with an
// explicit stack rather than by recursion, so no nesting can overflow the
// call stack (parse_xml also refuses nesting deeper than kMaxXmlDepth).
struct XmlNode {
  XmlNode() = default;
  XmlNode(const XmlNode&) = delete;
  XmlNode& operator=(const XmlNode&) = delete;
  ~XmlNode();

  std::string name;
  std::vector<std::pair<std::string, std::string>> attrs;
  std::string text;  // direct text content (not that of children)
  std::vector<std::unique_ptr<XmlNode>> children;

  const std::string* attr(std::string_view key) const {
    for (const auto& [k, v] : attrs)
      if (k == key) return &v;
    return nullptr;
  }
  const XmlNode* child(std::string_view n) const {
    for (const auto& c : children)
      if (c->name == n) return c.get();
    return nullptr;
  }
};

std::string xml_escape(std::string_view s);

// VTK's formats nest six elements deep; anything past this is refused by name.
inline constexpr std::size_t kMaxXmlDepth = 256;

struct ParsedXml {
  std::unique_ptr<XmlNode> root;
  std::optional<std::string> appended_encoding;  // set when <AppendedData> exists
  std::string_view appended;                       // bytes after the '_' marker
};

// Enough for VTK's XML files: elements, attributes, direct text; the
// <AppendedData> section is cut off before parsing because raw appended
// bytes may contain anything, including '<'.
ParsedXml parse_xml(std::string_view doc, const std::string& path);

std::optional<ScalarType> vtk_scalar(std::string_view t);
// VTK's name of a type ("UInt8", "Float32", ...), as DataArray type= writes it.
const char* vtk_type_name(ScalarType s);

struct Context {
  const std::string& path;
  bool big_endian = false;
  ScalarType header = ScalarType::UInt32;
  std::string compressor;  // "" or the compressor's class name
  std::optional<std::string> appended_encoding;
  std::string_view appended;
};

// Reads byte_order, header_type and compressor of the <VTKFile> root and the
// appended section into a Context; checks the root is a VTKFile of `type`.
Context file_context(const ParsedXml& xml, const std::string& path, std::string_view type);

// A decoded array: values in `bytes` of `type`, byte order `big`.
struct Array {
  ScalarType type = ScalarType::Float64;
  bool big = false;
  int components = 1;
  std::string bytes;
  std::size_t count() const { return bytes.size() / scalar_size(type); }
  // The common little-endian types inline (a file's whole arrays go
  // through here value by value), the rest through the general loads.
  double as_double(std::size_t i) const {
    const char* p = bytes.data() + i * scalar_size(type);
    // (A float32 NaN goes the general way, which quiets a signalling one, as
    // before.)
    if (!big && type == ScalarType::Float32) {
      const float f = mesh_bytes::load<float>(p, false);
      if (f == f) return f;
    }
    if (!big && type == ScalarType::Float64) return mesh_bytes::load<double>(p, false);
    return mesh_bytes::load_as_double(p, type, big);
  }
  bool as_int(std::size_t i, std::int64_t& v) const {
    const char* p = bytes.data() + i * scalar_size(type);
    if (!big && type == ScalarType::Int64) return v = mesh_bytes::load<std::int64_t>(p, false), true;
    if (!big && type == ScalarType::Int32) return v = mesh_bytes::load<std::int32_t>(p, false), true;
    if (!big && type == ScalarType::UInt32) return v = mesh_bytes::load<std::uint32_t>(p, false), true;
    return mesh_bytes::load_as_int64(p, type, big, v);
  }
};

// Decodes a <DataArray>. `expected` is the value count when known (-1 when not).
Array decode_array(const XmlNode& node, const Context& ctx, const std::string& what_in, std::int64_t expected);

// A non-negative count attribute (0 when absent); InputError when malformed.
std::int64_t count_attr(const XmlNode& node, std::string_view key, const std::string& path);

// The <DataArray Name="name"> child of a section, or null.
const XmlNode* named_array(const XmlNode* section, std::string_view name);

}  // namespace keymesh::io::vtk_xml
