#include "mesh_formats.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

#include <nlohmann/json.hpp>

#include "keymesh/core/error.hpp"
#include "keymesh/core/printable.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "keymesh/mesh/unit_normals.hpp"
#include "mesh_bytes.hpp"

namespace keymesh::io {

namespace {

// glTF stores little-endian data; the arrays are written straight from memory.
static_assert(std::endian::native == std::endian::little, "the .glb writer writes arrays in native byte order");

constexpr std::uint32_t kMagic = 0x46546C67;      // "glTF"
constexpr std::uint32_t kJsonChunk = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kBinChunk = 0x004E4942;   // "BIN\0"
constexpr int kFloat = 5126, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

std::uint64_t padded4(std::uint64_t n) { return (n + 3) & ~std::uint64_t{3}; }

// "mean_curvature" -> "_MEAN_CURVATURE": glTF reserves attribute names
// without a leading underscore for its own semantics.
std::string attribute_name(const std::string& field) {
  std::string out = "_";
  for (unsigned char c : field) out += std::isalnum(c) ? static_cast<char>(std::toupper(c)) : '_';
  return out;
}

// The attribute name of a field, once per primitive: glTF keys attributes
// by name, so a second field of the same name ("a b" and "a-b" both give
// _A_B; a second "Normals") would replace the first and leave its accessor
// unused. It is written as _A_B_2 (_3, ...) instead, with a warning.
std::string unique_attribute(const std::string& wanted, const nlohmann::json& attributes, const Field& f,
                             const std::string& path) {
  if (!attributes.contains(wanted)) return wanted;
  std::string name;
  for (int n = 2; name.empty() || attributes.contains(name); ++n) name = wanted + "_" + std::to_string(n);
  std::fprintf(stderr, "keymesh: warning: %s: point field '%s' written as glTF attribute %s (%s is another field's)\n",
               printable(path).c_str(), printable(f.name).c_str(), name.c_str(), wanted.c_str());
  return name;
}

// glTF forbids NaN and infinity in accessor data, and its min and max are
// JSON numbers: a field holding one is refused by name rather than written
// as "min":[null] (the Khronos validator's ACCESSOR_INVALID_FLOAT).
void require_finite(const Array<float>& values, int components, const std::string& field, const std::string& path) {
  std::size_t i = 0;
  while (i < values.size() && std::isfinite(values[i])) ++i;
  if (i == values.size()) return;
  throw InputError(path + ": point field '" + field + "' holds " + std::to_string(values[i]) + " at point " +
                   std::to_string(i / static_cast<std::size_t>(components)) +
                   ": glTF allows only finite numbers (write .ply or .vtp to keep it)");
}

const char* accessor_type(int components) {
  static const char* names[] = {"SCALAR", "VEC2", "VEC3", "VEC4"};
  return names[components - 1];
}

// One array of the BIN chunk: where its bytes come from and its place.
struct BinArray {
  const void* data;
  std::uint64_t bytes;
  std::uint64_t offset = 0;
};

// Per-component minimum and maximum of `count` tuples of `components` floats.
std::pair<nlohmann::json, nlohmann::json> float_bounds(const Array<float>& values, int components) {
  std::vector<float> lo(components, std::numeric_limits<float>::infinity());
  std::vector<float> hi(components, -std::numeric_limits<float>::infinity());
  for (std::size_t i = 0; i < values.size(); ++i) {
    const float v = values[i];
    const std::size_t c = i % static_cast<std::size_t>(components);
    lo[c] = std::min(lo[c], v);
    hi[c] = std::max(hi[c], v);
  }
  nlohmann::json jlo = nlohmann::json::array(), jhi = nlohmann::json::array();
  for (int c = 0; c < components; ++c) {
    jlo.push_back(static_cast<double>(lo[c]));
    jhi.push_back(static_cast<double>(hi[c]));
  }
  return {jlo, jhi};
}

// The triangles' indices: the cells as they are when all are triangles, fans
// of the polygons otherwise (in `fans`).
const Array<PointIndex>& triangle_indices(const SurfaceMesh& mesh, Array<PointIndex>& fans) {
  if (mesh.all_triangles()) return mesh.connectivity;
  for (Id c = 0; c < mesh.num_cells(); ++c) {
    const std::uint64_t b = mesh.cell_begin(c), e = mesh.cell_end(c);
    for (std::uint64_t k = b + 1; k + 1 < e; ++k)
      fans.insert(fans.end(), {mesh.connectivity[b], mesh.connectivity[k], mesh.connectivity[k + 1]});
  }
  return fans;
}

// The glTF document of one mesh of one primitive, and the arrays of its
// BIN chunk (pointing into the mesh and `indices`).
struct GlbContent {
  nlohmann::json doc;
  std::vector<BinArray> arrays;
  Array<float> unit_normals;  // the NORMAL array when the mesh's normals were not all unit vectors
};

// The accessors, buffer views and buffer of a mesh's points, point fields
// (1 to 4 components; Normals as NORMAL) and triangles. glTF requires
// NORMAL to hold unit vectors (the Khronos validator's
// ACCESSOR_VECTOR3_NON_UNIT): normals that are not (zero where a contour's
// triangles have zero area or its gradient vanishes, NaN from NaN data) are
// written as make_unit_normals (mesh/unit_normals.hpp) defines them.
void describe_mesh(const SurfaceMesh& mesh, const Array<PointIndex>& indices, GlbContent& glb,
                   const std::string& path) {
  nlohmann::json& doc = glb.doc;
  doc["nodes"] = nlohmann::json::array({{{"mesh", 0}}});
  nlohmann::json accessors = nlohmann::json::array(), views = nlohmann::json::array();
  std::uint64_t offset = 0;
  auto add_array = [&](const void* data, std::uint64_t bytes, int target) {
    glb.arrays.push_back(BinArray{data, bytes, offset});
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}, {"target", target}});
    offset = padded4(offset + bytes);
    return static_cast<int>(views.size()) - 1;
  };
  const auto count = static_cast<std::uint64_t>(mesh.num_points());
  auto add_float_attribute = [&](const Array<float>& values, int components) {
    const int view = add_array(values.data(), values.size() * sizeof(float), kArrayBuffer);
    auto [lo, hi] = float_bounds(values, components);
    accessors.push_back({{"bufferView", view}, {"componentType", kFloat}, {"count", count},
                         {"type", accessor_type(components)}, {"min", lo}, {"max", hi}});
    return static_cast<int>(accessors.size()) - 1;
  };
  nlohmann::json attributes;
  attributes["POSITION"] = add_float_attribute(mesh.points, 3);
  for (const Field& f : mesh.point_fields) {
    if (f.components < 1 || f.components > 4) continue;  // glTF has no wider vector accessor
    // The first 3-component "Normals" is NORMAL; another is an attribute as any field.
    const bool normals = f.name == "Normals" && f.components == 3 && !attributes.contains("NORMAL");
    const Array<float>* values = &f.values;
    if (normals) {
      glb.unit_normals = f.values;
      if (make_unit_normals(mesh, glb.unit_normals.data()) > 0) values = &glb.unit_normals;
    }
    require_finite(*values, f.components, f.name, path);
    const std::string name = unique_attribute(normals ? std::string("NORMAL") : attribute_name(f.name), attributes, f, path);
    attributes[name] = add_float_attribute(*values, f.components);
  }
  const int index_view = add_array(indices.data(), indices.size() * sizeof(PointIndex), kElementArrayBuffer);
  const auto [lo, hi] = std::minmax_element(indices.begin(), indices.end());
  accessors.push_back({{"bufferView", index_view}, {"componentType", kUnsignedInt}, {"count", indices.size()},
                       {"type", "SCALAR"}, {"min", {*lo}}, {"max", {*hi}}});
  doc["meshes"] = nlohmann::json::array(
      {{{"primitives", nlohmann::json::array({{{"attributes", attributes},
                                                {"indices", static_cast<int>(accessors.size()) - 1},
                                                {"mode", 4}}})}}});
  doc["accessors"] = std::move(accessors);
  doc["bufferViews"] = std::move(views);
  doc["buffers"] = nlohmann::json::array({{{"byteLength", offset}}});
}

// The .glb container: the 12-byte header, the JSON chunk (padded with
// spaces), and the BIN chunk when there are arrays (padded with zeros).
void write_glb(const GlbContent& glb, const std::string& path) {
  std::string json = glb.doc.dump();
  json.resize(padded4(json.size()), ' ');
  const auto& arrays = glb.arrays;
  const std::uint64_t bin = arrays.empty() ? 0 : padded4(arrays.back().offset + arrays.back().bytes);
  const std::uint64_t total = 12 + 8 + json.size() + (arrays.empty() ? 0 : 8 + bin);
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw LimitError(path + ": " + std::to_string(total) + " bytes exceed the 4 GiB a .glb can hold");

  AtomicFile file(path);
  std::string head;
  mesh_bytes::append_le(head, kMagic);
  mesh_bytes::append_le(head, std::uint32_t{2});
  mesh_bytes::append_le(head, static_cast<std::uint32_t>(total));
  mesh_bytes::append_le(head, static_cast<std::uint32_t>(json.size()));
  mesh_bytes::append_le(head, kJsonChunk);
  file.write(head);
  file.write(json);
  if (!arrays.empty()) {
    head.clear();
    mesh_bytes::append_le(head, static_cast<std::uint32_t>(bin));
    mesh_bytes::append_le(head, kBinChunk);
    file.write(head);
    static const char zeros[4] = {0, 0, 0, 0};
    std::uint64_t at = 0;
    for (const BinArray& a : arrays) {
      file.write(zeros, a.offset - at);
      file.write(a.data, a.bytes);
      at = a.offset + a.bytes;
    }
    file.write(zeros, bin - at);
  }
  file.commit();
}

}  // namespace

void write_gltf_binary(const SurfaceMesh& mesh, const std::string& path) {
  mesh_bytes::validate_mesh(mesh, path);
  Array<PointIndex> fans;
  const Array<PointIndex>& indices = triangle_indices(mesh, fans);
  GlbContent glb;
  glb.doc["asset"] = {{"version", "2.0"}, {"generator", "keymesh"}};
  glb.doc["scene"] = 0;
  glb.doc["scenes"] = nlohmann::json::array({{{"nodes", {0}}}});
  // Points no triangle uses would make an accessor of a mesh without a
  // primitive: an empty mesh is one empty node.
  if (indices.empty() || mesh.num_points() == 0) glb.doc["nodes"] = nlohmann::json::array({nlohmann::json::object()});
  else describe_mesh(mesh, indices, glb, path);
  write_glb(glb, path);
}

}  // namespace keymesh::io
