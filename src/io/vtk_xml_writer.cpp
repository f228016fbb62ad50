#include "vtk_xml_writer.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

#include "keymesh/io/atomic_file.hpp"
#include "mesh_bytes.hpp"
#include "vtk_xml.hpp"

namespace keymesh::io::vtk_xml {

namespace {

// Values converted per write: bounded memory whatever the array's size.
constexpr std::size_t kChunkValues = std::size_t(1) << 16;

// n values as the file stores them (little-endian T) into out.
template <class T>
void store_as(const std::int64_t* values, std::size_t n, std::string& out) {
  out.resize(n * sizeof(T));
  for (std::size_t i = 0; i < n; ++i) {
    T v = static_cast<T>(values[i]);
    if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) v = mesh_bytes::byteswap_value(v);
    std::memcpy(out.data() + i * sizeof(T), &v, sizeof(T));
  }
}

void store_chunk(ScalarType type, const std::int64_t* values, std::size_t n, std::string& out) {
  switch (type) {
    case ScalarType::UInt8: return store_as<std::uint8_t>(values, n, out);
    case ScalarType::Int32: return store_as<std::int32_t>(values, n, out);
    default: return store_as<std::int64_t>(values, n, out);
  }
}

// Bytes stored in native order, written little endian: as they are on a
// little-endian machine, each value's bytes reversed a chunk at a time on a
// big-endian one.
void write_native(AtomicFile& file, const void* data, std::uint64_t bytes, std::size_t value_size) {
  if (std::endian::native == std::endian::little || value_size == 1) {
    file.write(data, bytes);
    return;
  }
  const auto* src = static_cast<const char*>(data);
  std::string chunk;
  for (std::uint64_t at = 0; at < bytes; at += chunk.size()) {
    chunk.assign(src + at, static_cast<std::size_t>(std::min<std::uint64_t>(bytes - at, kChunkValues * value_size)));
    for (std::size_t v = 0; v < chunk.size(); v += value_size) std::reverse(&chunk[v], &chunk[v] + value_size);
    file.write(chunk);
  }
}

}  // namespace

std::string file_header(std::string_view type) {
  return "<?xml version=\"1.0\"?>\n<VTKFile type=\"" + std::string(type) +
         "\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
}

std::string field_attributes(const std::vector<Field>& fields) {
  std::string a;
  for (const Field& f : fields)
    if (f.components == 1) {
      a += " Scalars=\"" + xml_escape(f.name) + "\"";
      break;
    }
  for (const Field& f : fields)
    if (f.name == "Normals" && f.components == 3) {
      a += " Normals=\"Normals\"";
      break;
    }
  return a;
}

std::string AppendedArrays::floats(std::string_view name, int components, const keymesh::Array<float>& values) {
  return declare({ScalarType::Float32, values.size(), values.data(), {}}, name, components);
}

std::string AppendedArrays::bytes(ScalarType type, std::string_view name, int components, const void* data,
                                  std::uint64_t size) {
  return declare({type, size / scalar_size(type), data, {}}, name, components);
}

std::string AppendedArrays::integer_chunks(ScalarType type, std::string_view name, std::uint64_t count,
                                           ChunkFill fill) {
  return declare({type, count, nullptr, std::move(fill)}, name, 0);
}

std::string AppendedArrays::declare(Block block, std::string_view name, int components) {
  std::string line = std::string("        <DataArray type=\"") + vtk_type_name(block.type) + "\" Name=\"" +
                     xml_escape(name) + "\"";
  if (components > 0) line += " NumberOfComponents=\"" + std::to_string(components) + "\"";
  line += " format=\"appended\" offset=\"" + std::to_string(offset_) + "\"/>\n";
  offset_ += 8 + block.count * scalar_size(block.type);
  blocks_.push_back(std::move(block));
  return line;
}

void AppendedArrays::write(const std::string& path, std::string_view xml) const {
  AtomicFile file(path);
  file.write(xml);
  file.write(std::string_view("  <AppendedData encoding=\"raw\">\n   _"));
  std::string bytes;
  std::vector<std::int64_t> values;
  for (const Block& b : blocks_) {
    const std::size_t size = scalar_size(b.type);
    bytes.clear();
    mesh_bytes::append_le(bytes, static_cast<std::uint64_t>(b.count * size));
    file.write(bytes);
    if (b.data) {
      write_native(file, b.data, b.count * size, size);
      continue;
    }
    values.resize(static_cast<std::size_t>(std::min<std::uint64_t>(b.count, kChunkValues)));
    for (std::uint64_t at = 0; at < b.count; at += values.size()) {
      const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(values.size(), b.count - at));
      b.fill(at, n, values.data());
      store_chunk(b.type, values.data(), n, bytes);
      file.write(bytes);
    }
  }
  file.write(std::string_view("\n  </AppendedData>\n</VTKFile>\n"));
  file.commit();
}

}  // namespace keymesh::io::vtk_xml
