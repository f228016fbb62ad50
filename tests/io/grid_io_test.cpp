#include "keymesh/io/grid_io.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <bit>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "io/mesh_formats.hpp"
#include "io/mesh_bytes.hpp"
#include "zlib_bytes.hpp"

using namespace keymesh;

namespace {

// The process id keeps ctest's parallel runs of this file's tests (one process
// each) off each other's files: two tests write "poly.vtk".
std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("keymesh-gridio-" + std::to_string(::getpid()) + "-" + name))
      .string();
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Two cells of different types (a tet and a hexahedron sharing no points),
// a polygon of five corners, a point field and a 3-component cell field.
UnstructuredGrid mixed_grid(bool wide) {
  UnstructuredGrid g;
  for (int p = 0; p < 12; ++p) g.points.insert(g.points.end(), {float(p), float(p * p) * 0.5f, -float(p)});
  const std::uint64_t ids[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 11, 3, 0, 7, 9};
  g.connectivity = IndexArray::for_ids(wide ? (std::uint64_t(1) << 33) : 12, 17);
  for (int k = 0; k < 17; ++k) g.connectivity.set(k, ids[k]);
  g.offsets = {0, 4, 12, 17};
  g.cell_types = {std::uint8_t(CellType::Tetra), std::uint8_t(CellType::Hexahedron), std::uint8_t(CellType::Polygon)};
  g.point_fields.push_back({"temperature", 1, {}});
  for (int p = 0; p < 12; ++p) g.point_fields[0].values.push_back(0.25f * float(p) - 1.f);
  g.point_fields.push_back({"Normals", 3, {}});
  for (int p = 0; p < 36; ++p) g.point_fields[1].values.push_back(float(p % 3 == 0));
  g.point_fields.push_back({"stress tensor", 6, {}});
  for (int p = 0; p < 72; ++p) g.point_fields[2].values.push_back(1.f / float(p + 1));
  g.cell_fields.push_back({"velocity", 3, {1, 2, 3, -4, -5, -6, 7.5f, 8.5f, 9.5f}});
  g.cell_fields.push_back({"id", 1, {10, 20, 30}});
  return g;
}

void expect_same(const UnstructuredGrid& a, const UnstructuredGrid& b) {
  EXPECT_EQ(a.points, b.points);
  ASSERT_EQ(a.num_cells(), b.num_cells());
  ASSERT_EQ(a.connectivity.size(), b.connectivity.size());
  for (std::size_t k = 0; k < a.connectivity.size(); ++k) ASSERT_EQ(a.connectivity[k], b.connectivity[k]);
  for (Id c = 0; c < a.num_cells(); ++c) {
    ASSERT_EQ(a.cell_type(c), b.cell_type(c));
    ASSERT_EQ(a.cell_begin(c), b.cell_begin(c));
    ASSERT_EQ(a.cell_end(c), b.cell_end(c));
  }
  ASSERT_EQ(a.point_fields.size(), b.point_fields.size());
  for (std::size_t i = 0; i < a.point_fields.size(); ++i) {
    EXPECT_EQ(a.point_fields[i].name, b.point_fields[i].name);
    EXPECT_EQ(a.point_fields[i].components, b.point_fields[i].components);
    EXPECT_EQ(a.point_fields[i].values, b.point_fields[i].values);
  }
  ASSERT_EQ(a.cell_fields.size(), b.cell_fields.size());
  for (std::size_t i = 0; i < a.cell_fields.size(); ++i) {
    EXPECT_EQ(a.cell_fields[i].name, b.cell_fields[i].name);
    EXPECT_EQ(a.cell_fields[i].components, b.cell_fields[i].components);
    EXPECT_EQ(a.cell_fields[i].values, b.cell_fields[i].values);
  }
}

TEST(GridIo, RoundTripsMixedCellsThroughBothFormats) {
  for (bool wide : {false, true})
    for (const char* ext : {".vtu", ".vtk"}) {
      const UnstructuredGrid g = mixed_grid(wide);
      ASSERT_EQ(g.connectivity.wide(), wide);
      const std::string path = temp_path(std::string("mixed") + (wide ? "64" : "32") + ext);
      io::write_grid(g, path);
      EXPECT_TRUE(io::is_grid_file(path));
      const UnstructuredGrid back = io::read_grid(path);
      expect_same(g, back);
      // 12 points: the ids fit 32 bits however they were stored.
      EXPECT_FALSE(back.connectivity.wide());
      std::filesystem::remove(path);
    }
}

TEST(GridIo, VtuMarksNormalsAndTheFirstScalarAndUsesInt32IdsWhenTheyFit) {
  const UnstructuredGrid g = mixed_grid(true);
  const std::string path = temp_path("marks.vtu");
  io::write_grid(g, path);
  const std::string text = read_text(path);
  EXPECT_NE(text.find("<PointData Scalars=\"temperature\" Normals=\"Normals\">"), std::string::npos);
  EXPECT_NE(text.find("<CellData Scalars=\"id\">"), std::string::npos);
  EXPECT_NE(text.find("type=\"Int32\" Name=\"connectivity\""), std::string::npos);
  EXPECT_NE(text.find("header_type=\"UInt64\""), std::string::npos);
  EXPECT_NE(text.find("encoding=\"raw\""), std::string::npos);
  std::filesystem::remove(path);
}

TEST(GridIo, UniformTetsStayUniform) {
  for (bool wide : {false, true})
    for (const char* ext : {".vtu", ".vtk"}) {
      UnstructuredGrid g;
      g.points = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
      g.connectivity = IndexArray::for_ids(wide ? (std::uint64_t(1) << 40) : 5, 8);
      const std::uint64_t ids[] = {0, 1, 2, 3, 1, 2, 3, 4};
      for (int k = 0; k < 8; ++k) g.connectivity.set(k, ids[k]);
      const std::string path = temp_path(std::string("uniform") + ext);
      io::write_grid(g, path);
      const UnstructuredGrid back = io::read_grid(path);
      EXPECT_TRUE(back.uniform());
      EXPECT_TRUE(back.cell_types.empty());
      EXPECT_EQ(back.uniform_type, CellType::Tetra);
      expect_same(g, back);
      std::filesystem::remove(path);
    }
}

TEST(GridIo, EmptyGridRoundTrips) {
  for (const char* ext : {".vtu", ".vtk"}) {
    UnstructuredGrid g;
    const std::string path = temp_path(std::string("empty") + ext);
    io::write_grid(g, path);
    const UnstructuredGrid back = io::read_grid(path);
    EXPECT_EQ(back.num_points(), 0);
    EXPECT_EQ(back.num_cells(), 0);
    std::filesystem::remove(path);
  }
}

TEST(GridIo, ReadsHandWrittenAsciiFiles) {
  // One tet, written by hand in both formats; the expected arrays are the text's.
  const std::string vtu = temp_path("hand.vtu");
  write_text(vtu, R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="4" NumberOfCells="1">
      <PointData Scalars="s">
        <DataArray type="Float64" Name="s" format="ascii">0.5 1.5 2.5 3.5</DataArray>
      </PointData>
      <Points>
        <DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 0 0 1</DataArray>
      </Points>
      <Cells>
        <DataArray type="Int64" Name="connectivity" format="ascii">3 2 1 0</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">4</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">10</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
</VTKFile>
)");
  const std::string vtk = temp_path("hand.vtk");
  write_text(vtk, "# vtk DataFile Version 3.0\nhand written\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                  "POINTS 4 double\n0 0 0 1 0 0\n0 1 0 0 0 1\nCELLS 1 5\n4 3 2 1 0\nCELL_TYPES 1\n10\n"
                  "POINT_DATA 4\nSCALARS s float 1\nLOOKUP_TABLE default\n0.5 1.5 2.5 3.5\n");
  for (const std::string& path : {vtu, vtk}) {
    const UnstructuredGrid g = io::read_grid(path);
    ASSERT_EQ(g.num_points(), 4) << path;
    ASSERT_EQ(g.num_cells(), 1);
    EXPECT_EQ(g.cell_type(0), std::uint8_t(CellType::Tetra));
    EXPECT_EQ(g.connectivity[0], 3u);
    EXPECT_EQ(g.connectivity[3], 0u);
    EXPECT_EQ(g.points, (Array<float>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}));
    ASSERT_EQ(g.point_fields.size(), 1u);
    EXPECT_EQ(g.point_fields[0].name, "s");
    EXPECT_EQ(g.point_fields[0].values, (Array<float>{0.5f, 1.5f, 2.5f, 3.5f}));
    std::filesystem::remove(path);
  }
}

TEST(GridIo, ReadsSeveralAsciiPiecesWithIdsOffset) {
  // Piece 0: a triangle on 3 points; piece 1: a tet on 4 points, its ids
  // local to the piece; piece 2: empty (it must not drop the fields).
  const std::string path = temp_path("pieces.vtu");
  write_text(path, R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">
<UnstructuredGrid>
<Piece NumberOfPoints="3" NumberOfCells="1">
  <PointData><DataArray type="Int16" Name="t" format="ascii">1 2 3</DataArray></PointData>
  <CellData><DataArray type="UInt8" Name="c" NumberOfComponents="2" format="ascii">7 8</DataArray></CellData>
  <Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>
  <Cells><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2</DataArray>
    <DataArray type="UInt32" Name="offsets" format="ascii">3</DataArray>
    <DataArray type="UInt8" Name="types" format="ascii">5</DataArray></Cells>
</Piece>
<Piece NumberOfPoints="4" NumberOfCells="1">
  <PointData><DataArray type="Int16" Name="t" format="ascii">4 5 6 7</DataArray>
    <DataArray type="Float32" Name="only here" format="ascii">9 9 9 9</DataArray></PointData>
  <CellData><DataArray type="UInt8" Name="c" NumberOfComponents="2" format="ascii">9 10</DataArray></CellData>
  <Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 1 1 0 1 0 1 1 0 0 2</DataArray></Points>
  <Cells><DataArray type="Int64" Name="connectivity" format="ascii">3 2 1 0</DataArray>
    <DataArray type="Int64" Name="offsets" format="ascii">4</DataArray>
    <DataArray type="UInt8" Name="types" format="ascii">10</DataArray></Cells>
</Piece>
<Piece NumberOfPoints="0" NumberOfCells="0"/>
</UnstructuredGrid>
</VTKFile>
)");
  const UnstructuredGrid g = io::read_grid(path);
  ASSERT_EQ(g.num_points(), 7);
  ASSERT_EQ(g.num_cells(), 2);
  EXPECT_EQ(g.cell_type(0), std::uint8_t(CellType::Triangle));
  EXPECT_EQ(g.cell_type(1), std::uint8_t(CellType::Tetra));
  EXPECT_EQ(g.offsets, (std::vector<std::uint64_t>{0, 3, 7}));
  const std::vector<std::uint64_t> ids = {0, 1, 2, 6, 5, 4, 3};
  for (std::size_t k = 0; k < ids.size(); ++k) EXPECT_EQ(g.connectivity[k], ids[k]);
  EXPECT_EQ(g.points[3 * 6 + 2], 2.f);
  ASSERT_EQ(g.point_fields.size(), 1u);  // "only here" is not in every piece
  EXPECT_EQ(g.point_fields[0].name, "t");
  EXPECT_EQ(g.point_fields[0].values, (Array<float>{1, 2, 3, 4, 5, 6, 7}));
  ASSERT_EQ(g.cell_fields.size(), 1u);
  EXPECT_EQ(g.cell_fields[0].components, 2);
  EXPECT_EQ(g.cell_fields[0].values, (Array<float>{7, 8, 9, 10}));
  std::filesystem::remove(path);
}

// ---- binary .vtu in every encoding, built here byte by byte ----------------

template <class T>
void put(std::string& out, T v, bool big) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big == (std::endian::native == std::endian::little))
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

struct Encoding {
  bool big = false;
  bool header64 = false;
  bool zlib = false;
  int where = 0;  // 0 inline base64, 1 appended raw, 2 appended base64
};

// VTK's block layout for `data`: a byte-count header, or the compression
// header (blocks, block size, last block size, compressed sizes) and the
// zlib blocks (16 bytes each, so arrays span several blocks).
std::string vtk_block(const std::string& data, const Encoding& e) {
  std::string header, body;
  auto head = [&](std::uint64_t v) {
    if (e.header64) put<std::uint64_t>(header, v, e.big);
    else put<std::uint32_t>(header, std::uint32_t(v), e.big);
  };
  if (!e.zlib) {
    head(data.size());
    body = data;
  } else {
    const std::size_t bs = 16;
    const std::size_t blocks = (data.size() + bs - 1) / bs;
    std::vector<std::string> z;
    for (std::size_t b = 0; b < blocks; ++b) z.push_back(zlib_bytes(data.substr(b * bs, bs)));
    head(blocks);
    head(bs);
    head(data.size() % bs);
    for (const auto& c : z) head(c.size());
    for (const auto& c : z) body += c;
  }
  if (e.where == 1) return header + body;
  // VTK encodes the header and the data as two base64 runs when uncompressed.
  return io::mesh_bytes::base64_encode(header.data(), header.size()) +
         io::mesh_bytes::base64_encode(body.data(), body.size());
}

// One tet: points Float32 (0,0,0) (1,0,0) (0,1,0) (0,0,1); connectivity
// Int32 0 1 2 3; offsets Int64 4; types UInt8 10; point data "p" Float64
// 0.5 -1 2 1e10; cell data "q" UInt16 with 2 components 65535 3.
std::string binary_tet_vtu(const Encoding& e) {
  std::string pts, conn, offs, types, p, q;
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f}) put(pts, v, e.big);
  for (std::int32_t v : {0, 1, 2, 3}) put(conn, v, e.big);
  put<std::int64_t>(offs, 4, e.big);
  types.push_back(10);
  for (double v : {0.5, -1.0, 2.0, 1e10}) put(p, v, e.big);
  for (std::uint16_t v : {std::uint16_t(65535), std::uint16_t(3)}) put(q, v, e.big);
  std::string appended;
  auto array = [&](const char* type, const char* name, int comps, const std::string& data) {
    std::string x = std::string("<DataArray type=\"") + type + "\" Name=\"" + name + "\" NumberOfComponents=\"" +
                    std::to_string(comps) + "\" ";
    const std::string block = vtk_block(data, e);
    if (e.where == 0) return x + "format=\"binary\">\n" + block + "\n</DataArray>\n";
    x += "format=\"appended\" offset=\"" + std::to_string(appended.size()) + "\"/>\n";
    appended += block;
    return x;
  };
  std::string x = "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"";
  x += e.big ? "BigEndian" : "LittleEndian";
  x += std::string("\" header_type=\"") + (e.header64 ? "UInt64" : "UInt32") + "\"";
  if (e.zlib) x += " compressor=\"vtkZLibDataCompressor\"";
  x += ">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n";
  x += "<PointData Scalars=\"p\">\n" + array("Float64", "p", 1, p) + "</PointData>\n";
  x += "<CellData>\n" + array("UInt16", "q", 2, q) + "</CellData>\n";
  x += "<Points>\n" + array("Float32", "Points", 3, pts) + "</Points>\n";
  x += "<Cells>\n" + array("Int32", "connectivity", 1, conn) + array("Int64", "offsets", 1, offs) +
       array("UInt8", "types", 1, types) + "</Cells>\n";
  x += "</Piece>\n</UnstructuredGrid>\n";
  if (e.where != 0)
    x += std::string("<AppendedData encoding=\"") + (e.where == 1 ? "raw" : "base64") + "\">\n_" + appended +
         "\n</AppendedData>\n";
  return x + "</VTKFile>\n";
}

void expect_binary_tet(const UnstructuredGrid& g) {
  ASSERT_EQ(g.num_points(), 4);
  ASSERT_EQ(g.num_cells(), 1);
  EXPECT_EQ(g.points, (Array<float>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}));
  EXPECT_EQ(g.cell_type(0), std::uint8_t(CellType::Tetra));
  for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(g.connectivity[k], k);
  ASSERT_EQ(g.point_fields.size(), 1u);
  EXPECT_EQ(g.point_fields[0].values, (Array<float>{0.5f, -1.f, 2.f, 1e10f}));
  ASSERT_EQ(g.cell_fields.size(), 1u);
  EXPECT_EQ(g.cell_fields[0].components, 2);
  EXPECT_EQ(g.cell_fields[0].values, (Array<float>{65535.f, 3.f}));
}

TEST(GridIo, ReadsBinaryVtuInEveryEncoding) {
  for (bool big : {false, true})
    for (bool header64 : {false, true})
      for (bool zlib : {false, true})
        for (int where : {0, 1, 2}) {
          const Encoding e{big, header64, zlib, where};
          SCOPED_TRACE(testing::Message() << "big " << big << " header64 " << header64 << " zlib " << zlib
                                          << " where " << where);
          const std::string path = temp_path("enc.vtu");
          write_text(path, binary_tet_vtu(e));
          expect_binary_tet(io::read_grid(path));
          std::filesystem::remove(path);
        }
}

// ---- legacy .vtk ------------------------------------------------------------

TEST(GridIo, ReadsLegacy51AsciiWithAttributes) {
  // A tet (0 1 2 3) and a triangle (1 2 4) in 5.1's OFFSETS / CONNECTIVITY
  // layout, dataset-level FIELD data before POINTS, point VECTORS, NORMALS
  // and FIELD arrays (one with another tuple count, not kept), cell SCALARS.
  const std::string path = temp_path("v51.vtk");
  write_text(path, "# vtk DataFile Version 5.1\nfive one\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                   "FIELD FieldData 1\nTIME 1 1 double\n2.5\n"
                   "POINTS 5 float\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\n"
                   "CELLS 3 7\nOFFSETS vtktypeint64\n0 4 7\nCONNECTIVITY vtktypeint64\n0 1 2 3\n1 2 4\n"
                   "CELL_TYPES 2\n10\n5\n\n"
                   "POINT_DATA 5\nVECTORS v float\n1 2 3 4 5 6 7 8 9 10 11 12 13 14 15\n"
                   "NORMALS nn double\n0 0 1 0 0 1 0 0 1 0 0 1 0 0 1\n"
                   "FIELD FieldData 2\na 2 5 int\n-1 1 -2 2 -3 3 -4 4 -5 5\nb 1 3 float\n1 2 3\n"
                   "CELL_DATA 2\nSCALARS s int 1\nLOOKUP_TABLE default\n4 5\n");
  const UnstructuredGrid g = io::read_grid(path);
  ASSERT_EQ(g.num_points(), 5);
  ASSERT_EQ(g.num_cells(), 2);
  EXPECT_EQ(g.offsets, (std::vector<std::uint64_t>{0, 4, 7}));
  EXPECT_EQ(g.cell_types, (std::vector<std::uint8_t>{10, 5}));
  const std::vector<std::uint64_t> ids = {0, 1, 2, 3, 1, 2, 4};
  for (std::size_t k = 0; k < ids.size(); ++k) EXPECT_EQ(g.connectivity[k], ids[k]);
  ASSERT_EQ(g.point_fields.size(), 3u);
  EXPECT_EQ(g.point_fields[0].name, "v");
  EXPECT_EQ(g.point_fields[0].components, 3);
  EXPECT_EQ(g.point_fields[0].values[14], 15.f);
  EXPECT_EQ(g.point_fields[1].name, "Normals");
  EXPECT_EQ(g.point_fields[1].values[2], 1.f);
  EXPECT_EQ(g.point_fields[2].name, "a");
  EXPECT_EQ(g.point_fields[2].components, 2);
  EXPECT_EQ(g.point_fields[2].values, (Array<float>{-1, 1, -2, 2, -3, 3, -4, 4, -5, 5}));
  ASSERT_EQ(g.cell_fields.size(), 1u);
  EXPECT_EQ(g.cell_fields[0].values, (Array<float>{4, 5}));
  std::filesystem::remove(path);
}

TEST(GridIo, ReadsLegacyBinaryBuiltByHand) {
  // Big-endian: 4 double points, CELLS 2 9 (a tet, a triangle), CELL_TYPES,
  // point SCALARS with 2 components, cell SCALARS unsigned_char.
  std::string f = "# vtk DataFile Version 3.0\nbinary\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n";
  for (double v : {0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.}) put(f, v, true);
  f += "\nCELLS 2 9\n";
  for (std::int32_t v : {4, 3, 2, 1, 0, 3, 0, 1, 3}) put(f, v, true);
  f += "\nCELL_TYPES 2\n";
  for (std::int32_t v : {10, 5}) put(f, v, true);
  f += "\nPOINT_DATA 4\nSCALARS two float 2\nLOOKUP_TABLE default\n";
  for (float v : {1.f, 2.f, 3.f, 4.f, 5.f, 6.f, 7.f, 8.f}) put(f, v, true);
  f += "\nCELL_DATA 2\nSCALARS k unsigned_char\nLOOKUP_TABLE default\n";
  f += std::string("\x0a\xff", 2);  // 10 (a newline byte!) and 255
  f += "\n";
  const std::string path = temp_path("bin.vtk");
  write_text(path, f);
  const UnstructuredGrid g = io::read_grid(path);
  ASSERT_EQ(g.num_points(), 4);
  ASSERT_EQ(g.num_cells(), 2);
  EXPECT_EQ(g.points, (Array<float>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}));
  EXPECT_EQ(g.offsets, (std::vector<std::uint64_t>{0, 4, 7}));
  const std::vector<std::uint64_t> ids = {3, 2, 1, 0, 0, 1, 3};
  for (std::size_t k = 0; k < ids.size(); ++k) EXPECT_EQ(g.connectivity[k], ids[k]);
  ASSERT_EQ(g.point_fields.size(), 1u);
  EXPECT_EQ(g.point_fields[0].components, 2);
  EXPECT_EQ(g.point_fields[0].values, (Array<float>{1, 2, 3, 4, 5, 6, 7, 8}));
  ASSERT_EQ(g.cell_fields.size(), 1u);
  EXPECT_EQ(g.cell_fields[0].values, (Array<float>{10, 255}));
  std::filesystem::remove(path);
}

TEST(GridIo, LegacyWriterWritesBinary42) {
  const std::string path = temp_path("w42.vtk");
  io::write_grid(mixed_grid(false), path);
  const std::string text = read_text(path);
  EXPECT_EQ(text.rfind("# vtk DataFile Version 4.2\n", 0), 0u);
  EXPECT_NE(text.find("\nBINARY\nDATASET UNSTRUCTURED_GRID\n"), std::string::npos);
  EXPECT_NE(text.find("CELLS 3 20\n"), std::string::npos);  // 17 ids + 3 counts
  std::filesystem::remove(path);
}

TEST(GridIo, IsGridFileLooksAtTheLegacyHeader) {
  const std::string poly = temp_path("poly.vtk"), grid = temp_path("grid.vtk"), junk = temp_path("junk.vtk");
  write_text(poly, "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n");
  write_text(grid, "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 0 float\n");
  write_text(junk, std::string(5000, 'x'));
  EXPECT_FALSE(io::is_grid_file(poly));
  EXPECT_TRUE(io::is_grid_file(grid));
  EXPECT_FALSE(io::is_grid_file(junk));
  EXPECT_TRUE(io::is_grid_file("anything.vtu"));
  EXPECT_FALSE(io::is_grid_file("volume.vti"));
  for (const auto& p : {poly, grid, junk}) std::filesystem::remove(p);
}

// ---- malformed input --------------------------------------------------------

void expect_input_error(const std::string& name, const std::string& text, const std::string& needle) {
  const std::string path = temp_path(name);
  write_text(path, text);
  try {
    io::read_grid(path);
    ADD_FAILURE() << name << ": no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_NE(m.find(needle), std::string::npos) << name << ": " << m;
  }
  std::filesystem::remove(path);
}

TEST(GridIo, MalformedLegacyFilesAreRefusedByName) {
  const std::string head = "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  const std::string pts = "POINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\n";
  expect_input_error("poly.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n",
                     "POLYDATA");
  expect_input_error("sp.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n",
                     "STRUCTURED_POINTS");
  expect_input_error("notvtk.vtk", "hello\n", "not a legacy VTK file");
  expect_input_error("mode.vtk", "# vtk DataFile Version 3.0\nx\nXML\nDATASET UNSTRUCTURED_GRID\n", "not ASCII or BINARY");
  expect_input_error("trunc.vtk", head + "POINTS 4 float\n0 0 0 1 0 0\n", "file ends");
  expect_input_error("nopoints.vtk", head + "CELL_TYPES 0\n", "no POINTS");
  expect_input_error("range.vtk", head + pts + "CELLS 1 5\n4 0 1 2 9\nCELL_TYPES 1\n10\n", "out of range");
  expect_input_error("neg.vtk", head + pts + "CELLS 1 5\n4 0 1 2 -1\nCELL_TYPES 1\n10\n", "out of range");
  expect_input_error("cells.vtk", head + pts + "CELLS 1 5\n7 0 1 2 3\nCELL_TYPES 1\n10\n", "inconsistent");
  expect_input_error("size.vtk", head + pts + "CELLS 2 1\n1 0\nCELL_TYPES 2\n1 1\n", "smaller");
  expect_input_error("short.vtk", head + pts + "CELLS 1 6\n4 0 1 2 3 7\nCELL_TYPES 1\n10\n", "inconsistent");
  expect_input_error("types.vtk", head + pts + "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 2\n10 10\n", "CELL_TYPES");
  expect_input_error("badtype.vtk", head + pts + "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n99\n", "type 99");
  expect_input_error("corners.vtk", head + pts + "CELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n10\n", "3 corners");
  expect_input_error("ptype.vtk", head + "POINTS 4 quaternion\n", "unknown point type");
  expect_input_error("keyword.vtk", head + pts + "BANANAS 3\n", "unexpected keyword 'BANANAS'");
  expect_input_error("pdcount.vtk", head + pts + "POINT_DATA 5\nSCALARS s float\n1 2 3 4 5\n", "does not match");
  expect_input_error("count.vtk", head + "POINTS -4 float\n", "bad point count");
  expect_input_error("huge.vtk", head + "POINTS 99999999999999999 float\n", "larger than any file");
  expect_input_error("nan.vtk", head + "POINTS 1 float\n0 zero 0\n", "not a number");
  expect_input_error("off51.vtk", head + pts + "CELLS 2 4\nOFFSETS vtktypeint64\n0 9\nCONNECTIVITY vtktypeint64\n0 1 2 3\n",
                     "outside the connectivity");
  expect_input_error("dec51.vtk",
                     head + pts + "CELLS 4 6\nOFFSETS vtktypeint64\n0 4 3 6\nCONNECTIVITY vtktypeint64\n0 1 2 3 1 2\n"
                                  "CELL_TYPES 3\n10 5 5\n",
                     "decrease");
  expect_input_error("bin.vtk", "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 100000000 float\n\1\2",
                     "file ends first");
  std::string bin_cells = "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 float\n";
  for (float v : {0.f, 0.f, 0.f}) put(bin_cells, v, true);
  bin_cells += "\nCELLS 1 2\n";
  put<std::int32_t>(bin_cells, 1, true);
  expect_input_error("bincells.vtk", bin_cells, "file ends first");
}

std::string one_piece(const std::string& piece, const std::string& root_attrs = "byte_order=\"LittleEndian\"") {
  return "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" " + root_attrs +
         ">\n<UnstructuredGrid>" + piece + "</UnstructuredGrid></VTKFile>\n";
}

std::string tet_piece(const std::string& conn, const std::string& offs, const std::string& types,
                      const std::string& extra = "", const char* counts = "NumberOfPoints=\"4\" NumberOfCells=\"1\"") {
  return std::string("<Piece ") + counts + "><Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">" +
         "0 0 0 1 0 0 0 1 0 0 0 1</DataArray></Points><Cells>" +
         "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">" + conn + "</DataArray>" +
         "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">" + offs + "</DataArray>" +
         "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">" + types + "</DataArray></Cells>" + extra +
         "</Piece>";
}

TEST(GridIo, MalformedVtuFilesAreRefusedByName) {
  expect_input_error("ok-control.vtu", one_piece(tet_piece("0 1 2 3", "4", "10") + "<Piece"), "malformed XML");
  expect_input_error("huge.vtu", one_piece("<Piece NumberOfPoints=\"4000000000\" NumberOfCells=\"0\"><Points>"
                                           "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0"
                                           "</DataArray></Points></Piece>"),
                     "expected 12000000000");
  expect_input_error("negative.vtu", one_piece("<Piece NumberOfPoints=\"-4\" NumberOfCells=\"0\"/>"), "bad NumberOfPoints");
  expect_input_error("overflow.vtu", one_piece("<Piece NumberOfPoints=\"99999999999999999999\" NumberOfCells=\"0\"/>"),
                     "bad NumberOfPoints");
  expect_input_error("cellrange.vtu", one_piece(tet_piece("0 1 2 5", "4", "10")), "out of range");
  expect_input_error("negid.vtu", one_piece(tet_piece("0 1 -2 3", "4", "10")), "out of range");
  expect_input_error("offcount.vtu", one_piece(tet_piece("0 1 2 3", "4", "10", "", "NumberOfPoints=\"4\" NumberOfCells=\"2\"")),
                     "expected 2");
  expect_input_error("offend.vtu", one_piece(tet_piece("0 1 2 3", "3", "10")), "end at 3");
  expect_input_error("offdec.vtu",
                     one_piece(tet_piece("0 1 2 0 1 2", "3 2", "5 5", "", "NumberOfPoints=\"4\" NumberOfCells=\"2\"")),
                     "decrease");
  expect_input_error("badtype.vtu", one_piece(tet_piece("0 1 2 3", "4", "99")), "type 99");
  expect_input_error("typerange.vtu", one_piece(tet_piece("0 1 2 3", "4", "300")), "cell type 300");
  expect_input_error("corners.vtu", one_piece(tet_piece("0 1 2", "3", "10")), "3 corners");
  expect_input_error("field.vtu",
                     one_piece(tet_piece("0 1 2 3", "4", "10",
                                         "<PointData><DataArray type=\"Float32\" Name=\"f\" format=\"ascii\">1 2 3"
                                         "</DataArray></PointData>")),
                     "3 values for 4 tuples");
  expect_input_error("number.vtu", one_piece(tet_piece("0 1 2 x", "4", "10")), "bad number 'x'");
  expect_input_error("nocells.vtu", one_piece("<Piece NumberOfPoints=\"0\" NumberOfCells=\"1\"/>"), "lacks");
  expect_input_error("nopiece.vtu", one_piece(""), "no <Piece>");
  expect_input_error("root.vtu", "<foo/>", "not a VTK XML file");
  expect_input_error("kind.vtu", "<VTKFile type=\"PolyData\"><PolyData/></VTKFile>", "is not UnstructuredGrid");
  expect_input_error("unclosed.vtu", "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid>", "truncated XML");
  expect_input_error("header.vtu", one_piece(tet_piece("0 1 2 3", "4", "10"), "header_type=\"UInt16\""),
                     "unsupported header_type");

  // Binary encodings broken after the fact.
  const Encoding raw{false, false, false, 1}, zipped{false, false, true, 1}, b64{false, false, false, 0};
  std::string doc = binary_tet_vtu(raw);
  expect_input_error("truncated.vtu", doc.substr(0, doc.size() - 60), "");
  doc = binary_tet_vtu(b64);
  std::string bad = doc;
  bad[bad.find("format=\"binary\">\n") + 20] = '*';
  expect_input_error("base64.vtu", bad, "invalid base64 character");
  bad = doc;
  const std::size_t data_at = bad.find("format=\"binary\">\n") + 17;
  bad.erase(data_at + 8, bad.find("\n</DataArray>", data_at) - data_at - 8);  // keep only the header's base64
  expect_input_error("base64short.vtu", bad, "more than the file holds");
  // zlib: a compressed block whose bytes are garbled.
  doc = binary_tet_vtu(zipped);
  bad = doc;
  const std::size_t app = bad.find("\n_") + 2;
  // The first array (point data "p", 32 bytes = 2 blocks) has a 20-byte header; its first block follows.
  bad[app + 20 + 3] = static_cast<char>(bad[app + 20 + 3] ^ 0x55);
  bad[app + 20 + 4] = static_cast<char>(bad[app + 20 + 4] ^ 0x55);
  expect_input_error("zlib.vtu", bad, "zlib");
  // zlib: a block that inflates past its declared size (16 bytes declared as 8).
  bad = doc;
  std::uint32_t eight = 8;
  std::memcpy(&bad[app + 4], &eight, 4);  // block size 16 -> 8 (last size 0: every block full)
  expect_input_error("zlibsize.vtu", bad, "zlib");
  // Block count that no file could hold.
  bad = doc;
  const std::uint32_t many = 0x7fffffff;
  std::memcpy(&bad[app], &many, 4);
  expect_input_error("blocks.vtu", bad, "more than the file holds");
  // Uncompressed size header larger than the file.
  doc = binary_tet_vtu(raw);
  bad = doc;
  const std::size_t app2 = bad.find("\n_") + 2;
  const std::uint32_t lots = 0x7ffffff0;
  std::memcpy(&bad[app2], &lots, 4);
  expect_input_error("rawsize.vtu", bad, "more than the file holds");
}

TEST(GridIo, UnwritableOutputLeavesNothing) {
  const UnstructuredGrid g = mixed_grid(false);
  EXPECT_THROW(io::write_grid(g, "/nonexistent-dir/x.vtu"), InputError);
  EXPECT_THROW(io::write_grid(g, "/nonexistent-dir/x.vtk"), InputError);
  EXPECT_THROW(io::write_grid(g, temp_path("x.abc")), InputError);
  EXPECT_THROW(io::read_grid(temp_path("x.abc")), InputError);
  EXPECT_FALSE(std::filesystem::exists("/nonexistent-dir/x.vtu"));
  UnstructuredGrid bad = g;
  bad.connectivity.set(0, 99);  // out of range: refused before anything is written
  const std::string path = temp_path("bad.vtu");
  EXPECT_THROW(io::write_grid(bad, path), InputError);
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
