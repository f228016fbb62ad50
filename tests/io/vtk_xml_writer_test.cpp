// The VTK XML appended-data writer (src/io/vtk_xml_writer.hpp), read back by
// the independently written DataArray decoder of the readers (vtk_xml.hpp):
// every array, converted or written from memory, longer than one conversion
// chunk or empty, comes back with its values at the offset it declared.
#include "io/vtk_xml_writer.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "io/mesh_bytes.hpp"
#include "io/vtk_xml.hpp"

using namespace keymesh;
using namespace keymesh::io;

TEST(VtkXmlWriter, EveryArrayReadsBackAtItsOffset) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("keymesh_vtk_xml_writer_" + std::to_string(::getpid()) + ".vtp"))
                               .string();
  // Past the writer's 65536-value chunks, so conversion crosses chunk ends.
  const std::uint64_t n = 200003;
  Array<float> floats(3 * n);  // every value set below
  for (std::size_t i = 0; i < floats.size(); ++i) floats[i] = static_cast<float>(i) * 0.25f - 7.0f;
  std::vector<std::int32_t> stored(n);
  for (std::uint64_t i = 0; i < n; ++i) stored[i] = static_cast<std::int32_t>(i * 3) - 5;
  const Array<float> none;

  vtk_xml::AppendedArrays arrays;
  std::string x = vtk_xml::file_header("PolyData") + "  <PolyData>\n    <Piece>\n      <PointData>\n";
  x += arrays.floats("f<&>", 3, floats);
  x += arrays.integers(ScalarType::Int64, "big", n, [](std::uint64_t i) { return std::int64_t(i) * 40000000000 - 9; });
  x += arrays.integers(ScalarType::Int32, "small", n, [](std::uint64_t i) { return std::int64_t(i % 1000) - 500; });
  x += arrays.integers(ScalarType::UInt8, "bytes", n, [](std::uint64_t i) { return i % 251; });
  x += arrays.bytes(ScalarType::Int32, "stored", 0, stored.data(), 4 * n);
  x += arrays.floats("empty", 1, none);
  x += "      </PointData>\n    </Piece>\n  </PolyData>\n";
  arrays.write(path, x);

  const std::string data(mesh_bytes::read_whole_file(path).view());
  std::filesystem::remove(path);
  const vtk_xml::ParsedXml xml = vtk_xml::parse_xml(data, path);
  const vtk_xml::Context ctx = vtk_xml::file_context(xml, path, "PolyData");
  const vtk_xml::XmlNode* section = xml.root->child("PolyData")->child("Piece")->child("PointData");
  auto array = [&](const char* name, std::int64_t count) {
    const vtk_xml::XmlNode* node = vtk_xml::named_array(section, name);
    EXPECT_NE(node, nullptr) << name;
    return vtk_xml::decode_array(*node, ctx, name, count);
  };
  const vtk_xml::Array f = array("f<&>", std::int64_t(3 * n));
  ASSERT_EQ(f.count(), 3 * n);
  for (std::size_t i = 0; i < floats.size(); ++i) ASSERT_EQ(f.as_double(i), floats[i]) << i;
  const vtk_xml::Array big = array("big", std::int64_t(n)), small = array("small", std::int64_t(n));
  const vtk_xml::Array bytes = array("bytes", std::int64_t(n)), from_memory = array("stored", std::int64_t(n));
  EXPECT_EQ(big.type, ScalarType::Int64);
  EXPECT_EQ(small.type, ScalarType::Int32);
  EXPECT_EQ(bytes.type, ScalarType::UInt8);
  for (std::uint64_t i = 0; i < n; ++i) {
    std::int64_t v = 0;
    ASSERT_TRUE(big.as_int(i, v) && v == std::int64_t(i) * 40000000000 - 9) << i;
    ASSERT_TRUE(small.as_int(i, v) && v == std::int64_t(i % 1000) - 500) << i;
    ASSERT_TRUE(bytes.as_int(i, v) && v == std::int64_t(i % 251)) << i;
    ASSERT_TRUE(from_memory.as_int(i, v) && v == stored[i]) << i;
  }
  EXPECT_EQ(array("empty", 0).count(), 0u);
}
