#include "keymesh/io/mesh_io.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "keymesh/core/error.hpp"
#include "io/mesh_bytes.hpp"
#include "io/mesh_formats.hpp"

using namespace keymesh;
namespace fs = std::filesystem;

namespace {

// A fresh directory per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() /
            ("keymesh_meshio_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" + info->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string read_text(const std::string& path) { return std::string(io::mesh_bytes::read_whole_file(path).view()); }

// Tetrahedron with a 3-component "Normals", a scalar and a vector field.
SurfaceMesh sample_mesh() {
  SurfaceMesh m;
  m.points = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1.5f};
  m.connectivity = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  m.point_fields.push_back({"Normals", 3, {-0.57f, -0.57f, -0.57f, 1, 0, 0, 0, 1, 0, 0, 0, 1}});
  m.point_fields.push_back({"temperature", 1, {1.5f, -2.25f, 3.0f, 1e-7f}});
  m.point_fields.push_back({"velocity", 3, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}});
  return m;
}

// A triangle, a quad and a pentagon sharing points.
SurfaceMesh polygon_mesh() {
  SurfaceMesh m;
  m.points = {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0, 3, 0.5f, 0, 1, 2, 0};
  m.connectivity = {0, 1, 4, 3, 1, 2, 6, 5, 4, 3, 4, 7};
  m.offsets = {0, 4, 9, 12};
  return m;
}

const Field* field(const SurfaceMesh& m, const std::string& name) { return m.find_point_field(name); }

void expect_same_geometry(const SurfaceMesh& a, const SurfaceMesh& b) {
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.connectivity, b.connectivity);
  EXPECT_EQ(a.offsets, b.offsets);
}

void expect_field(const SurfaceMesh& got, const Field& want) {
  const Field* f = field(got, want.name);
  ASSERT_NE(f, nullptr) << "missing field " << want.name;
  EXPECT_EQ(f->components, want.components) << want.name;
  EXPECT_EQ(f->values, want.values) << want.name;
}

// Every truncation of a valid file must either parse or throw InputError/LimitError.
template <class Parse>
void expect_no_crash_on_truncation(const std::string& data, Parse parse) {
  const std::size_t step = std::max<std::size_t>(1, data.size() / 200);
  for (std::size_t len = 0; len < data.size(); len += step) {
    try {
      parse(std::string_view(data).substr(0, len));
    } catch (const InputError&) {
    } catch (const LimitError&) {
    }
  }
  // And random byte flips.
  std::mt19937 rng(1234);
  for (int trial = 0; trial < 300; ++trial) {
    std::string bad = data;
    for (int k = 0; k < 4; ++k) bad[rng() % bad.size()] = static_cast<char>(rng() & 255);
    try {
      parse(bad);
    } catch (const InputError&) {
    } catch (const LimitError&) {
    }
  }
}

bool have_vtk() { return std::system("/usr/bin/python3 -c 'import vtk' >/dev/null 2>&1") == 0; }

int run_python(const TempDir& dir, const std::string& script) {
  const std::string py = dir.file("script.py");
  write_text(py, script);
  const std::string cmd = "cd '" + dir.path().string() + "' && /usr/bin/python3 '" + py + "' > '" +
                          dir.file("python.log") + "' 2>&1";
  const int rc = std::system(cmd.c_str());
  if (rc != 0) std::fprintf(stderr, "python failed:\n%s\n", read_text(dir.file("python.log")).c_str());
  return rc;
}

}  // namespace

// ---------------------------------------------------------------- PLY

TEST(PlyTest, RoundTripWithFields) {
  TempDir dir;
  const SurfaceMesh m = sample_mesh();
  io::write_mesh(m, dir.file("a.ply"));
  const std::string text = read_text(dir.file("a.ply"));
  EXPECT_NE(text.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(text.find("property float nx\nproperty float ny\nproperty float nz\n"), std::string::npos);
  EXPECT_NE(text.find("property float velocity_2\n"), std::string::npos);
  EXPECT_NE(text.find("property list uchar uint vertex_indices"), std::string::npos);
  const SurfaceMesh r = io::read_mesh(dir.file("a.ply"));
  expect_same_geometry(m, r);
  ASSERT_EQ(r.point_fields.size(), 3u);
  for (const Field& f : m.point_fields) expect_field(r, f);
}

TEST(PlyTest, Polygons) {
  TempDir dir;
  const SurfaceMesh m = polygon_mesh();
  io::write_mesh(m, dir.file("p.ply"));
  expect_same_geometry(m, io::read_mesh(dir.file("p.ply")));
}

TEST(PlyTest, HandWrittenAscii) {
  TempDir dir;
  write_text(dir.file("h.ply"),
             "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\n"
             "element vertex 4\r\nproperty double x\r\nproperty double y\r\nproperty double z\r\n"
             "property uchar red\r\nproperty float nx\r\nproperty float ny\r\nproperty float nz\r\n"
             "property list uchar int junk\r\n"
             "element face 2\r\nproperty uchar flags\r\nproperty list uchar int vertex_indices\r\n"
             "element material 1\r\nproperty float shine\r\n"
             "end_header\r\n"
             "0 0 0 255 0 0 1 2 7 8\r\n1 0 0 0 0 0 1 0\r\n1 1 0 10 0 0 1 1 3\r\n0 1 0 20 0 0 1 0\r\n"
             "9 4 0 1 2 3\r\n9 3 0 2 3\r\n0.5\r\n");
  const SurfaceMesh r = io::read_mesh(dir.file("h.ply"));
  EXPECT_EQ(r.points, (Array<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}));
  EXPECT_EQ(r.connectivity, (Array<PointIndex>{0, 1, 2, 3, 0, 2, 3}));
  EXPECT_EQ(r.offsets, (Array<std::uint64_t>{0, 4, 7}));
  expect_field(r, {"red", 1, {255, 0, 10, 20}});
  expect_field(r, {"Normals", 3, {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}});
}

TEST(PlyTest, BinaryBigEndianWithShortIndices) {
  std::string d =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list int ushort vertex_indices\nend_header\n";
  auto be32 = [&](std::uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) d += static_cast<char>((v >> s) & 255);
  };
  auto bef = [&](float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, 4);
    be32(u);
  };
  const float pts[9] = {0, 0, 0, 2, 0, 0, 0, 3, 0.5f};
  for (float f : pts) bef(f);
  be32(3);
  for (int i : {2, 1, 0}) {
    d += '\0';
    d += static_cast<char>(i);
  }
  const SurfaceMesh r = io::parse_ply(d, "mem.ply");
  EXPECT_EQ(r.points, Array<float>(pts, pts + 9));
  EXPECT_EQ(r.connectivity, (Array<PointIndex>{2, 1, 0}));
  EXPECT_TRUE(r.offsets.empty());
}

TEST(PlyTest, MalformedInputsThrow) {
  const std::string good_header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  EXPECT_THROW(io::parse_ply("plx\nformat ascii 1.0\nend_header\n", "m.ply"), InputError);
  EXPECT_THROW(io::parse_ply("ply\nformat ascii 1.0\nelement vertex 3\n", "m.ply"), InputError);  // no end_header
  EXPECT_THROW(io::parse_ply(good_header + "0 0 0 1 0 0 0 1 0 3 0 1 3\n", "m.ply"), InputError);  // index 3 of 3
  EXPECT_THROW(io::parse_ply(good_header + "0 0 0 1 0 0 0 1 0 3 0 -1 2\n", "m.ply"), InputError);  // negative
  EXPECT_THROW(io::parse_ply(good_header + "0 0 0 1 0 0 0 1 0 3 0 1\n", "m.ply"), InputError);     // truncated
  EXPECT_THROW(io::parse_ply(good_header + "0 0 0 1 0 zz 0 1 0 3 0 1 2\n", "m.ply"), InputError);  // not a number
  // A count the file cannot hold is refused before allocating.
  const std::string huge =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n";
  EXPECT_THROW(io::parse_ply(huge + std::string(100, '\0'), "m.ply"), InputError);
  try {
    io::parse_ply(good_header + "0 0 0 1 0 0 0 1 0 3 0 1 3\n", "where.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("where.ply"), std::string::npos);
  }
}

TEST(PlyTest, NoCrashOnGarbage) {
  TempDir dir;
  io::write_mesh(polygon_mesh(), dir.file("p.ply"));
  expect_no_crash_on_truncation(read_text(dir.file("p.ply")), [](std::string_view d) { io::parse_ply(d, "g.ply"); });
}

// ---------------------------------------------------------------- OBJ

TEST(ObjTest, RoundTripWithNormals) {
  TempDir dir;
  const SurfaceMesh m = sample_mesh();
  io::write_mesh(m, dir.file("a.obj"));
  const std::string text = read_text(dir.file("a.obj"));
  EXPECT_NE(text.find("f 1//1 3//3 2//2"), std::string::npos);
  const SurfaceMesh r = io::read_mesh(dir.file("a.obj"));
  expect_same_geometry(m, r);
  ASSERT_EQ(r.point_fields.size(), 1u);  // OBJ keeps normals only
  expect_field(r, m.point_fields[0]);
}

TEST(ObjTest, Polygons) {
  TempDir dir;
  const SurfaceMesh m = polygon_mesh();
  io::write_mesh(m, dir.file("p.obj"));
  const SurfaceMesh r = io::read_mesh(dir.file("p.obj"));
  expect_same_geometry(m, r);
  EXPECT_TRUE(r.point_fields.empty());
}

TEST(ObjTest, FaceFormsAndRelativeIndices) {
  const std::string text =
      "# comment\nmtllib x.mtl\no thing\nv 0 0 0\nv 1 0 0 1.0\nv 1 1 0 0.5 0.5 0.5\nv 0 1 0\n"
      "vt 0 0\nvt 1 0\nvn 0 0 1\ng group\nusemtl m\ns off\n"
      "f 1/1 2/2 3/1\nf 1/1/1 3/2/1 4/1/1\nf -4//1 -2//1 -1//1\nl 1 2\n";
  const SurfaceMesh r = io::parse_obj(text, "m.obj");
  EXPECT_EQ(r.points.size(), 12u);
  EXPECT_EQ(r.connectivity, (Array<PointIndex>{0, 1, 2, 0, 2, 3, 0, 2, 3}));
  EXPECT_TRUE(r.offsets.empty());
  EXPECT_TRUE(r.point_fields.empty());  // not every corner names a normal
}

TEST(ObjTest, MalformedInputsThrow) {
  EXPECT_THROW(io::parse_obj("v 0 0 0\nv 1 0 0\nf 1 2 3\n", "m.obj"), InputError);
  EXPECT_THROW(io::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "m.obj"), InputError);
  EXPECT_THROW(io::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n", "m.obj"), InputError);
  EXPECT_THROW(io::parse_obj("v 0 0\n", "m.obj"), InputError);
  EXPECT_THROW(io::parse_obj("v 0 0 0\nv 1 0 0\nf 1 2\n", "m.obj"), InputError);
  EXPECT_THROW(io::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "m.obj"), InputError);
}

TEST(ObjTest, NoCrashOnGarbage) {
  TempDir dir;
  io::write_mesh(sample_mesh(), dir.file("p.obj"));
  expect_no_crash_on_truncation(read_text(dir.file("p.obj")), [](std::string_view d) { io::parse_obj(d, "g.obj"); });
}

// ---------------------------------------------------------------- STL

namespace {
// Each cell's corner positions, in cell order: what STL preserves.
std::vector<float> corner_positions(const SurfaceMesh& m) {
  std::vector<float> out;
  for (Id c = 0; c < m.num_cells(); ++c) {
    const std::uint64_t b = m.cell_begin(c), e = m.cell_end(c);
    for (std::uint64_t k = b + 1; k + 1 < e; ++k)
      for (std::uint64_t q : {b, k, k + 1})
        for (int a = 0; a < 3; ++a) out.push_back(m.points[3 * m.connectivity[q] + a]);
  }
  return out;
}
}  // namespace

TEST(StlTest, RoundTripWeldsPoints) {
  TempDir dir;
  const SurfaceMesh m = sample_mesh();
  io::write_mesh(m, dir.file("a.stl"));
  EXPECT_EQ(fs::file_size(dir.file("a.stl")), 84u + 50u * 4u);
  const SurfaceMesh r = io::read_mesh(dir.file("a.stl"));
  EXPECT_EQ(r.num_points(), 4);
  EXPECT_EQ(r.num_cells(), 4);
  EXPECT_TRUE(r.point_fields.empty());
  EXPECT_EQ(corner_positions(r), corner_positions(m));
  // Points numbered by first appearance: cell 0 is (0, 1, 2).
  EXPECT_EQ(r.connectivity[0], 0u);
  EXPECT_EQ(r.connectivity[1], 1u);
  EXPECT_EQ(r.connectivity[2], 2u);
  // The written facet normal of cell 0 is the unit normal of (p0, p2, p1).
  const std::string data = read_text(dir.file("a.stl"));
  float nrm[3];
  std::memcpy(nrm, data.data() + 84, 12);
  EXPECT_FLOAT_EQ(nrm[0], 0.0f);
  EXPECT_FLOAT_EQ(nrm[1], 0.0f);
  EXPECT_FLOAT_EQ(nrm[2], -1.0f);
}

TEST(StlTest, PolygonsAreFanTriangulated) {
  TempDir dir;
  const SurfaceMesh m = polygon_mesh();
  io::write_mesh(m, dir.file("p.stl"));
  const SurfaceMesh r = io::read_mesh(dir.file("p.stl"));
  EXPECT_EQ(r.num_cells(), 2 + 3 + 1);
  EXPECT_EQ(r.num_points(), 8);
  EXPECT_EQ(corner_positions(r), corner_positions(m));
}

TEST(StlTest, HandWrittenAscii) {
  const std::string text =
      "solid square made by hand\n"
      "  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 0 0\n      vertex 1 1 0\n"
      "    endloop\n  endfacet\n"
      "  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 1 0\n      vertex 0 1 0e0\n"
      "    endloop\n  endfacet\n"
      "endsolid square\n"
      "solid second\nfacet normal 0 0 0\nouter loop\nvertex 1 1 0\nvertex 1 0 0\nvertex 2 0 0\nendloop\nendfacet\n"
      "endsolid\n";
  const SurfaceMesh r = io::parse_stl(text, "s.stl");
  EXPECT_EQ(r.points, (Array<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0}));
  EXPECT_EQ(r.connectivity, (Array<PointIndex>{0, 1, 2, 0, 2, 3, 2, 1, 4}));
}

TEST(StlTest, BinaryWithSolidHeader) {
  std::string d = "solid this is really binary";
  d.resize(80, ' ');
  const std::uint32_t one = 1;
  d.append(reinterpret_cast<const char*>(&one), 4);
  const float vals[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  d.append(reinterpret_cast<const char*>(vals), sizeof vals);
  d.append(2, '\0');
  const SurfaceMesh r = io::parse_stl(d, "b.stl");
  EXPECT_EQ(r.num_points(), 3);
  EXPECT_EQ(r.connectivity, (Array<PointIndex>{0, 1, 2}));
}

TEST(StlTest, MalformedInputsThrow) {
  std::string d(80, 'x');
  const std::uint32_t many = 1000000;
  d.append(reinterpret_cast<const char*>(&many), 4);
  d.append(500, '\0');
  EXPECT_THROW(io::parse_stl(d, "t.stl"), InputError);  // truncated binary
  EXPECT_THROW(io::parse_stl("hello", "t.stl"), InputError);
  EXPECT_THROW(io::parse_stl("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nendloop\n", "t.stl"), InputError);
  EXPECT_THROW(io::parse_stl("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0", "t.stl"), InputError);
}

TEST(StlTest, NoCrashOnGarbage) {
  TempDir dir;
  io::write_mesh(polygon_mesh(), dir.file("p.stl"));
  expect_no_crash_on_truncation(read_text(dir.file("p.stl")), [](std::string_view d) { io::parse_stl(d, "g.stl"); });
  const std::string ascii =
      "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\nendsolid a\n";
  expect_no_crash_on_truncation(ascii, [](std::string_view d) { io::parse_stl(d, "g.stl"); });
}

// ---------------------------------------------------------------- VTP

TEST(VtpTest, RoundTripWithFields) {
  TempDir dir;
  const SurfaceMesh m = sample_mesh();
  io::write_mesh(m, dir.file("a.vtp"));
  const std::string text = read_text(dir.file("a.vtp"));
  EXPECT_NE(text.find("<AppendedData encoding=\"raw\">"), std::string::npos);
  EXPECT_NE(text.find("Normals=\"Normals\""), std::string::npos);
  EXPECT_NE(text.find("Scalars=\"temperature\""), std::string::npos);
  const SurfaceMesh r = io::read_mesh(dir.file("a.vtp"));
  expect_same_geometry(m, r);
  ASSERT_EQ(r.point_fields.size(), 3u);
  for (const Field& f : m.point_fields) expect_field(r, f);
}

TEST(VtpTest, Polygons) {
  TempDir dir;
  const SurfaceMesh m = polygon_mesh();
  io::write_mesh(m, dir.file("p.vtp"));
  expect_same_geometry(m, io::read_mesh(dir.file("p.vtp")));
}

TEST(VtpTest, HandWrittenAsciiAndBase64) {
  // One piece ascii, one piece base64 (uncompressed, UInt32 header), plus a strip.
  const float pts[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::string raw;
  const std::uint32_t nbytes = sizeof pts;
  raw.append(reinterpret_cast<const char*>(&nbytes), 4);
  raw.append(reinterpret_cast<const char*>(pts), sizeof pts);
  const std::string b64 = io::mesh_bytes::base64_encode(raw.data(), raw.size());
  const std::string xml =
      "<?xml version=\"1.0\"?>\n<!-- hand made -->\n"
      "<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>\n"
      "<Piece NumberOfPoints=\"4\" NumberOfPolys=\"1\" NumberOfStrips=\"1\">\n"
      "<PointData><DataArray type=\"Float64\" Name=\"a&amp;b\" format=\"ascii\">1 2 3 4</DataArray>"
      "<DataArray type=\"String\" Name=\"labels\" format=\"ascii\">65 0</DataArray></PointData>\n"
      "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 1 1 0 0 1 0"
      "</DataArray></Points>\n"
      "<Polys><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray></Polys>\n"
      "<Strips><DataArray type=\"UInt8\" Name=\"connectivity\" format=\"ascii\">0 1 3 2</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"offsets\" format=\"ascii\">4</DataArray></Strips>\n"
      "</Piece>\n"
      "<Piece NumberOfPoints=\"3\" NumberOfPolys=\"1\">\n"
      "<PointData><DataArray type=\"Float32\" Name=\"a&amp;b\" format=\"ascii\">5 6 7</DataArray></PointData>\n"
      "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"binary\">\n  " + b64 +
      "\n</DataArray></Points>\n"
      "<Polys><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">2 1 0</DataArray>"
      "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">3</DataArray></Polys>\n"
      "</Piece>\n</PolyData>\n</VTKFile>\n";
  const SurfaceMesh r = io::parse_vtp(xml, "h.vtp");
  EXPECT_EQ(r.num_points(), 7);
  EXPECT_EQ(r.connectivity, (Array<PointIndex>{0, 1, 2, 3, 0, 1, 3, 3, 1, 2, 6, 5, 4}));
  EXPECT_EQ(r.offsets, (Array<std::uint64_t>{0, 4, 7, 10, 13}));
  expect_field(r, {"a&b", 1, {1, 2, 3, 4, 5, 6, 7}});
  EXPECT_EQ(r.point_fields.size(), 1u);
}

TEST(VtpTest, ArrayMarkedAsNormalsIsNamedNormals) {
  const std::string xml =
      "<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"3\" NumberOfPolys=\"1\">"
      "<PointData Normals=\"nrm\"><DataArray type=\"Float32\" Name=\"nrm\" NumberOfComponents=\"3\" "
      "format=\"ascii\">0 0 1 0 0 1 0 0 1</DataArray></PointData><Points>"
      "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 0</DataArray></Points>"
      "<Polys><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2</DataArray>"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">3</DataArray></Polys></Piece></PolyData></VTKFile>";
  const SurfaceMesh r = io::parse_vtp(xml, "n.vtp");
  expect_field(r, {"Normals", 3, {0, 0, 1, 0, 0, 1, 0, 0, 1}});
}

TEST(VtpTest, MalformedInputsThrow) {
  TempDir dir;
  io::write_mesh(sample_mesh(), dir.file("a.vtp"));
  const std::string good = read_text(dir.file("a.vtp"));
  EXPECT_THROW(io::parse_vtp("not xml at all", "m.vtp"), InputError);
  EXPECT_THROW(io::parse_vtp("<VTKFile type=\"ImageData\"></VTKFile>", "m.vtp"), InputError);
  EXPECT_THROW(io::parse_vtp(good.substr(0, good.size() / 2), "m.vtp"), InputError);
  EXPECT_THROW(io::parse_vtp(good.substr(0, good.find(">\n   _") + 25), "m.vtp"), InputError);
  // NumberOfPoints the data does not back.
  std::string lie = good;
  lie.replace(lie.find("NumberOfPoints=\"4\""), 18, "NumberOfPoints=\"400000000000\"");
  EXPECT_THROW(io::parse_vtp(lie, "m.vtp"), InputError);
  const std::string head =
      "<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"3\" NumberOfPolys=\"1\"><Points>"
      "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 0</DataArray></Points>"
      "<Polys><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">";
  const std::string tail = "</DataArray><DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">3</DataArray>"
                           "</Polys></Piece></PolyData></VTKFile>";
  EXPECT_NO_THROW(io::parse_vtp(head + "0 1 2" + tail, "m.vtp"));
  EXPECT_THROW(io::parse_vtp(head + "0 1 3" + tail, "m.vtp"), InputError);
  EXPECT_THROW(io::parse_vtp(head + "0 -1 2" + tail, "m.vtp"), InputError);
  EXPECT_THROW(io::parse_vtp(head + "0 1" + tail, "m.vtp"), InputError);
  // A huge appended byte count.
  std::string huge = good;
  const std::size_t us = huge.find(">\n   _") + 4;
  const std::uint64_t big = 1ull << 60;
  std::memcpy(&huge[us + 1], &big, 8);
  EXPECT_THROW(io::parse_vtp(huge, "m.vtp"), InputError);
}

TEST(VtpTest, NoCrashOnGarbage) {
  TempDir dir;
  io::write_mesh(sample_mesh(), dir.file("a.vtp"));
  expect_no_crash_on_truncation(read_text(dir.file("a.vtp")), [](std::string_view d) { io::parse_vtp(d, "g.vtp"); });
}

// VTK reads keymesh's files and keymesh reads VTK's (ascii, binary + zlib,
// appended base64 + zlib, appended raw, UInt32/UInt64 headers).
TEST(VtpTest, VtkInterop) {
  if (!have_vtk()) GTEST_SKIP() << "python3-vtk9 not importable";
  TempDir dir;
  SurfaceMesh m = polygon_mesh();
  m.point_fields.push_back({"Normals", 3, Array<float>(3 * 8, 0.0f)});
  for (int i = 0; i < 8; ++i) m.point_fields.back().values[3 * i + 2] = 1.0f;
  m.point_fields.push_back({"height", 1, {0, 1, 2, 3, 4, 5, 6, 7.5f}});
  m.point_fields.push_back({"vel", 2, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15}});
  io::write_mesh(m, dir.file("keymesh.vtp"));

  const std::string script = R"PY(
import vtk
r = vtk.vtkXMLPolyDataReader()
r.SetFileName('keymesh.vtp')
r.Update()
if r.GetErrorCode() != 0:
    raise SystemExit('vtk reader error %d' % r.GetErrorCode())
pd = r.GetOutput()
with open('vtk_saw.txt', 'w') as f:
    f.write('%d %d\n' % (pd.GetNumberOfPoints(), pd.GetNumberOfPolys()))
    for i in range(pd.GetNumberOfPoints()):
        f.write('%r %r %r\n' % pd.GetPoint(i))
    ids = vtk.vtkIdList()
    polys = pd.GetPolys()
    polys.InitTraversal()
    while polys.GetNextCell(ids):
        f.write(' '.join(str(ids.GetId(k)) for k in range(ids.GetNumberOfIds())) + '\n')
    p = pd.GetPointData()
    f.write('normals %s\n' % (p.GetNormals().GetName() if p.GetNormals() else 'none'))
    f.write('scalars %s\n' % (p.GetScalars().GetName() if p.GetScalars() else 'none'))
    a = p.GetArray('vel')
    f.write('vel %d %r\n' % (a.GetNumberOfComponents(), a.GetComponent(7, 1)))

# Files written by VTK itself, in every mode.
s = vtk.vtkSphereSource()
s.SetThetaResolution(9)
s.SetPhiResolution(7)
s.Update()
src = s.GetOutput()
h = vtk.vtkFloatArray()
h.SetName('height')
for i in range(src.GetNumberOfPoints()):
    h.InsertNextValue(src.GetPoint(i)[2] * 3.0)
src.GetPointData().AddArray(h)
quad = vtk.vtkPolyData()
def write(name, mode, compress, encode=True, header64=False):
    w = vtk.vtkXMLPolyDataWriter()
    w.SetInputData(src)
    w.SetFileName(name)
    getattr(w, 'SetDataModeTo' + mode)()
    if not compress:
        w.SetCompressorTypeToNone()
    if header64:
        w.SetHeaderTypeToUInt64()
    if not encode:
        w.EncodeAppendedDataOff()
    w.SetBlockSize(256)  # several zlib blocks per array
    w.Write()
write('vtk_ascii.vtp', 'Ascii', True)
write('vtk_binary_zlib.vtp', 'Binary', True)
write('vtk_binary.vtp', 'Binary', False)
write('vtk_appended_zlib.vtp', 'Appended', True)
write('vtk_appended_raw.vtp', 'Appended', False, encode=False)
write('vtk_appended_raw_zlib64.vtp', 'Appended', True, encode=False, header64=True)
write('vtk_binary64.vtp', 'Binary', False, header64=True)
with open('vtk_truth.txt', 'w') as f:
    f.write('%d %d\n' % (src.GetNumberOfPoints(), src.GetNumberOfPolys()))
    for i in range(src.GetNumberOfPoints()):
        f.write('%r %r %r %r\n' % (src.GetPoint(i) + (h.GetValue(i),)))
    ids = vtk.vtkIdList()
    polys = src.GetPolys()
    polys.InitTraversal()
    while polys.GetNextCell(ids):
        f.write(' '.join(str(ids.GetId(k)) for k in range(ids.GetNumberOfIds())) + '\n')
)PY";
  ASSERT_EQ(run_python(dir, script), 0);

  // What VTK saw in keymesh's file.
  {
    std::istringstream in(read_text(dir.file("vtk_saw.txt")));
    Id np = 0, nc = 0;
    in >> np >> nc;
    ASSERT_EQ(np, m.num_points());
    ASSERT_EQ(nc, m.num_cells());
    for (Id i = 0; i < np; ++i)
      for (int a = 0; a < 3; ++a) {
        double v;
        in >> v;
        EXPECT_EQ(static_cast<float>(v), m.points[3 * i + a]);
      }
    std::string line;
    std::getline(in, line);
    for (Id c = 0; c < nc; ++c) {
      std::getline(in, line);
      std::istringstream ls(line);
      std::vector<PointIndex> ids;
      for (PointIndex id; ls >> id;) ids.push_back(id);
      EXPECT_EQ(ids, std::vector<PointIndex>(m.connectivity.begin() + m.cell_begin(c),
                                             m.connectivity.begin() + m.cell_end(c)));
    }
    std::string key, value;
    in >> key >> value;
    EXPECT_EQ(key + " " + value, "normals Normals");
    in >> key >> value;
    EXPECT_EQ(key + " " + value, "scalars height");
    int comps = 0;
    double v71 = 0;
    in >> key >> comps >> v71;
    EXPECT_EQ(comps, 2);
    EXPECT_EQ(v71, 15.0);
  }

  // What keymesh reads from VTK's files.
  std::istringstream truth(read_text(dir.file("vtk_truth.txt")));
  Id np = 0, nc = 0;
  truth >> np >> nc;
  std::vector<float> pts, height;
  for (Id i = 0; i < np; ++i) {
    double x, y, z, hv;
    truth >> x >> y >> z >> hv;
    pts.insert(pts.end(), {float(x), float(y), float(z)});
    height.push_back(float(hv));
  }
  Array<PointIndex> conn;
  for (PointIndex id; truth >> id;) conn.push_back(id);
  ASSERT_EQ(conn.size(), 3u * nc);
  for (const char* name : {"vtk_ascii.vtp", "vtk_binary_zlib.vtp", "vtk_binary.vtp", "vtk_appended_zlib.vtp",
                           "vtk_appended_raw.vtp", "vtk_appended_raw_zlib64.vtp", "vtk_binary64.vtp"}) {
    SCOPED_TRACE(name);
    const SurfaceMesh r = io::read_mesh(dir.file(name));
    ASSERT_EQ(r.num_points(), np);
    for (std::size_t i = 0; i < pts.size(); ++i) EXPECT_NEAR(r.points[i], pts[i], 1e-6f);
    EXPECT_EQ(r.connectivity, conn);
    EXPECT_TRUE(r.offsets.empty());
    const Field* hf = field(r, "height");
    ASSERT_NE(hf, nullptr);
    for (Id i = 0; i < np; ++i) EXPECT_NEAR(hf->values[i], height[i], 1e-6f);
    const Field* nf = field(r, "Normals");
    ASSERT_NE(nf, nullptr);
    EXPECT_EQ(nf->components, 3);
  }
}

// ---------------------------------------------------------------- dispatch

TEST(MeshIoTest, UnknownExtensionNamesFileAndFormats) {
  TempDir dir;
  std::ofstream(dir.file("some_mesh.xyz")) << "x";  // a missing one is refused as missing
  EXPECT_THROW(io::read_mesh(dir.file("missing.xyz")), InputError);
  try {
    io::read_mesh(dir.file("some_mesh.xyz"));
    FAIL();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("some_mesh.xyz"), std::string::npos);
    EXPECT_NE(msg.find(".ply"), std::string::npos);
    EXPECT_NE(msg.find(".vtp"), std::string::npos);
  }
  EXPECT_THROW(io::write_mesh(sample_mesh(), "/tmp/no_extension"), InputError);
}

TEST(MeshIoTest, ExtensionIsCaseInsensitive) {
  TempDir dir;
  io::write_mesh(sample_mesh(), dir.file("UPPER.PLY"));
  EXPECT_EQ(io::read_mesh(dir.file("UPPER.PLY")).num_cells(), 4);
}

TEST(MeshIoTest, WritingIntoMissingDirectoryThrowsAndLeavesNoFile) {
  TempDir dir;
  for (const char* ext : {".ply", ".obj", ".stl", ".vtp"}) {
    const std::string path = dir.file("missing/sub/mesh") + ext;
    EXPECT_THROW(io::write_mesh(sample_mesh(), path), InputError) << ext;
    EXPECT_FALSE(fs::exists(path));
  }
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(MeshIoTest, InvalidMeshIsRefusedWithoutWriting) {
  TempDir dir;
  SurfaceMesh m = sample_mesh();
  m.connectivity[3] = 99;
  for (const char* ext : {".ply", ".obj", ".stl", ".vtp"}) {
    const std::string path = dir.file("bad") + ext;
    EXPECT_THROW(io::write_mesh(m, path), InputError) << ext;
    EXPECT_FALSE(fs::exists(path));
  }
  EXPECT_TRUE(fs::is_empty(dir.path()));  // no temporary left behind either
}

TEST(MeshIoTest, MissingFileThrows) {
  for (const char* ext : {".ply", ".obj", ".stl", ".vtp"})
    EXPECT_THROW(io::read_mesh(std::string("/nonexistent/keymesh/mesh") + ext), InputError);
}

TEST(MeshIoTest, EmptyMeshRoundTrips) {
  TempDir dir;
  for (const char* ext : {".ply", ".obj", ".vtp", ".stl"}) {
    io::write_mesh(SurfaceMesh{}, dir.file("empty") + ext);
    const SurfaceMesh r = io::read_mesh(dir.file("empty") + ext);
    EXPECT_EQ(r.num_points(), 0) << ext;
    EXPECT_EQ(r.num_cells(), 0) << ext;
  }
}

// ---- .pvtp: pieces welded by their global point ids -------------------------------

// A square of two triangles split into two pieces that share the diagonal's
// two points (global ids 1 and 2), as a distributed run writes them.
TEST(PvtpTest, PiecesWeldByGlobalIdsNotPositions) {
  TempDir dir;
  SurfaceMesh a, b;
  a.points = {0, 0, 0, 1, 0, 0, 0, 1, 0};  // global 0, 1, 2
  a.connectivity = {0, 1, 2};
  a.point_fields.push_back({"s", 1, {10, 11, 12}});
  b.points = {0, 1, 0, 1, 0, 0, 1, 1, 0};  // global 2, 1, 3
  b.connectivity = {1, 2, 0};
  b.point_fields.push_back({"s", 1, {12, 11, 13}});
  const std::vector<std::uint64_t> ia = {0, 1, 2}, ib = {2, 1, 3};
  io::write_vtp(a, dir.file("sq_0.vtp"), &ia);
  io::write_vtp(b, dir.file("sq_1.vtp"), &ib);
  io::write_pvtp(dir.file("sq.pvtp"), a, {"sq_0.vtp", "sq_1.vtp"}, true);
  const SurfaceMesh m = io::read_mesh(dir.file("sq.pvtp"));
  EXPECT_EQ(m.points, (Array<float>{0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0}));
  EXPECT_EQ(m.connectivity, (Array<PointIndex>{0, 1, 2, 1, 3, 2}));
  ASSERT_EQ(m.point_fields.size(), 1u);  // the ids are not a field
  EXPECT_EQ(m.point_fields[0].values, (Array<float>{10, 11, 12, 13}));
  // Copies that disagree on a position, ids past the points held, a missing piece.
  SurfaceMesh moved = b;
  moved.points[0] = 0.5f;
  io::write_vtp(moved, dir.file("sq_1.vtp"), &ib);
  EXPECT_THROW(io::read_mesh(dir.file("sq.pvtp")), InputError);
  const std::vector<std::uint64_t> far = {2, 1, 1000000000};
  io::write_vtp(b, dir.file("sq_1.vtp"), &far);
  EXPECT_THROW(io::read_mesh(dir.file("sq.pvtp")), InputError);
  fs::remove(dir.file("sq_1.vtp"));
  EXPECT_THROW(io::read_mesh(dir.file("sq.pvtp")), InputError);
  // Pieces without ids sit side by side (3 + 3 points: nothing welded).
  io::write_vtp(b, dir.file("sq_1.vtp"));
  io::write_vtp(a, dir.file("sq_0.vtp"));
  EXPECT_EQ(io::read_mesh(dir.file("sq.pvtp")).num_points(), 6);
  write_text(dir.file("not.pvtp"), "<VTKFile type=\"PolyData\"/>");
  EXPECT_THROW(io::read_mesh(dir.file("not.pvtp")), InputError);
}

// The same square written as distributed pieces with VTK's ghost marks:
// each piece carries the other's triangle as a ghost cell (DUPLICATECELL)
// and marks the points the other owns (DUPLICATEPOINT). The reader drops
// ghost cells (the square's two triangles, once each), keeps no
// vtkGhostType field, and takes a point's field from its owner's copy.
TEST(PvtpTest, GhostCellsAreDroppedAndOwnersFieldsKept) {
  TempDir dir;
  SurfaceMesh a, b;
  a.points = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};  // global 0, 1, 2, 3 (3 a ghost point)
  a.connectivity = {0, 1, 2, 2, 1, 3};              // its triangle, then b's as a ghost cell
  a.point_fields.push_back({"s", 1, {10, -1, -2, -3}});
  b.points = {0, 1, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0};  // global 2, 1, 3, 0 (0 a ghost point)
  b.connectivity = {0, 1, 2, 3, 1, 0};              // its triangle, then a's as a ghost cell
  b.point_fields.push_back({"s", 1, {12, 11, 13, -4}});
  const std::vector<std::uint64_t> ia = {0, 1, 2, 3}, ib = {2, 1, 3, 0};
  const io::PieceGhosts ga{{0, 1, 1, 1}, {0, 1}}, gb{{0, 0, 0, 1}, {0, 1}};
  io::write_vtp(a, dir.file("sq_0.vtp"), &ia, &ga);
  io::write_vtp(b, dir.file("sq_1.vtp"), &ib, &gb);
  io::write_pvtp(dir.file("sq.pvtp"), a, {"sq_0.vtp", "sq_1.vtp"}, true, true);
  const SurfaceMesh m = io::read_mesh(dir.file("sq.pvtp"));
  EXPECT_EQ(m.points, (Array<float>{0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0}));
  EXPECT_EQ(m.connectivity, (Array<PointIndex>{0, 1, 2, 2, 1, 3}));
  ASSERT_EQ(m.point_fields.size(), 1u);  // neither the ids nor the marks are fields
  EXPECT_EQ(m.point_fields[0].values, (Array<float>{10, 11, 12, 13}));
  EXPECT_TRUE(m.cell_fields.empty());
  // A lone piece read as a .vtp: its own triangle, its points as they are.
  const SurfaceMesh lone = io::read_mesh(dir.file("sq_0.vtp"));
  EXPECT_EQ(lone.connectivity, (Array<PointIndex>{0, 1, 2}));
  EXPECT_EQ(lone.num_points(), 4);
  EXPECT_TRUE(lone.cell_fields.empty());
  const io::PieceGhosts short_marks{{0, 1}, {0, 1}};
  EXPECT_THROW(io::write_vtp(a, dir.file("bad.vtp"), &ia, &short_marks), InputError);
}

// The binary PLY readers of whole records (vertex records in place, 13-byte
// triangles, then faces of any size) give what the ASCII reader gives for
// the same values: meshes of mostly triangles with polygons among them
// (first, middle, last), in every common layout of counts, ids and extra
// properties; and refuse a bad face by its index wherever it falls.
TEST(PlyTest, BinaryRecordsReadAsTheirAsciiText) {
  std::mt19937 rng(11);
  struct Layout {
    const char* count;
    const char* id;
    bool face_extra, vertex_extra;
  };
  const Layout layouts[] = {{"uchar", "uint", false, false}, {"uchar", "int", false, true},
                            {"int", "int", false, false},    {"uchar", "uint", true, false},
                            {"ushort", "uint", false, true}};
  auto put = [](std::string& d, auto v) { d.append(reinterpret_cast<const char*>(&v), sizeof v); };
  for (int round = 0; round < 40; ++round) {
    const Layout& L = layouts[round % 5];
    const int n_points = 5 + static_cast<int>(rng() % 50), n_faces = 1 + static_cast<int>(rng() % 60);
    std::vector<std::vector<std::uint32_t>> faces(static_cast<std::size_t>(n_faces));
    for (int f = 0; f < n_faces; ++f) {
      const bool polygon = rng() % 6 == 0 || (round % 3 == 0 && (f == 0 || f == n_faces - 1));
      faces[f].resize(polygon ? 4 + rng() % 3 : 3);
      for (auto& id : faces[f]) id = rng() % static_cast<std::uint32_t>(n_points);
    }
    std::ostringstream header, text;
    header << "element vertex " << n_points << "\nproperty float x\nproperty float y\nproperty float z\n"
           << (L.vertex_extra ? "property double w\n" : "") << "element face " << n_faces << "\n"
           << (L.face_extra ? "property uchar flags\n" : "") << "property list " << L.count << " " << L.id
           << " vertex_indices\nend_header\n";
    text << "ply\nformat ascii 1.0\n" << header.str();
    std::string bin = "ply\nformat binary_little_endian 1.0\n";
    bin += header.str();
    text.precision(9);
    for (int p = 0; p < n_points; ++p) {
      const float xyz[3] = {static_cast<float>(rng() % 1000) / 8, static_cast<float>(p), -0.5f * p};
      for (float c : xyz) text << c << " ", put(bin, c);
      if (L.vertex_extra) text << p * 0.25 << " ", put(bin, p * 0.25);
      text << "\n";
    }
    for (const auto& f : faces) {
      if (L.face_extra) text << "7 ", put(bin, std::uint8_t{7});
      text << f.size();
      if (std::string(L.count) == "uchar") put(bin, static_cast<std::uint8_t>(f.size()));
      else if (std::string(L.count) == "ushort") put(bin, static_cast<std::uint16_t>(f.size()));
      else put(bin, static_cast<std::int32_t>(f.size()));
      for (std::uint32_t id : f) text << " " << id, put(bin, id);
      text << "\n";
    }
    const SurfaceMesh a = io::parse_ply(text.str(), "a.ply"), b = io::parse_ply(bin, "b.ply");
    EXPECT_EQ(a.points, b.points) << round;
    EXPECT_EQ(a.connectivity, b.connectivity) << round;
    EXPECT_EQ(a.offsets, b.offsets) << round;
    ASSERT_EQ(a.point_fields.size(), b.point_fields.size());
    for (std::size_t f = 0; f < a.point_fields.size(); ++f) EXPECT_EQ(a.point_fields[f].values, b.point_fields[f].values);
    // A bad face k (an id past the points, a negative int id, two ids, or
    // the file cut inside it): refused, naming face k or the truncation.
    const std::size_t k = rng() % faces.size();
    std::size_t at = bin.size();
    for (std::size_t f = faces.size(); f-- > k;)
      at -= (L.face_extra ? 1 : 0) + (std::string(L.count) == "uchar" ? 1 : std::string(L.count) == "ushort" ? 2 : 4) +
            4 * faces[f].size();
    const std::size_t ids = at + (L.face_extra ? 1 : 0) + (std::string(L.count) == "uchar" ? 1 : std::string(L.count) == "ushort" ? 2 : 4);
    auto refused = [&](const std::string& data, const std::string& says, const std::string& or_says = "") {
      try {
        io::parse_ply(data, "b.ply");
        ADD_FAILURE() << "accepted, round " << round << ", face " << k;
      } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_TRUE(what.find(says) != std::string::npos || (!or_says.empty() && what.find(or_says) != std::string::npos))
            << what << " / " << says;
      }
    };
    for (std::size_t j = 0; j < faces[k].size(); ++j) {
      std::string past = bin;
      const auto n = static_cast<std::uint32_t>(n_points);
      std::memcpy(&past[ids + 4 * j], &n, 4);
      refused(past, "face " + std::to_string(k) + " refers to vertex " + std::to_string(n_points));
    }
    if (std::string(L.id) == "int") {
      std::string negative = bin;
      const std::int32_t minus = -1;
      std::memcpy(&negative[ids], &minus, 4);
      refused(negative, "face " + std::to_string(k) + " refers to vertex -1");
    }
    if (std::string(L.count) == "uchar") {
      std::string two = bin;
      two[ids - 1] = 2;
      refused(two, "face " + std::to_string(k) + " has 2 vertices");
    }
    refused(bin.substr(0, ids + 2), "truncated", "more than the file can hold");
  }
}
