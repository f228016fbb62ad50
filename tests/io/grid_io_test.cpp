#include "keymesh/io/grid_io.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/io/legacy_vtk.hpp"
#include "keymesh/io/vtu.hpp"

using namespace keymesh;

namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("keymesh-gridio-" + name)).string();
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// Two cells of different types (a tet and a hexahedron sharing no points),
// a point field and a 3-component cell field.
UnstructuredGrid mixed_grid(bool wide) {
  UnstructuredGrid g;
  for (int p = 0; p < 12; ++p) g.points.insert(g.points.end(), {float(p), float(p * p) * 0.5f, -float(p)});
  const std::uint64_t ids[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  g.connectivity = IndexArray::for_ids(wide ? (std::uint64_t(1) << 33) : 12, 12);
  for (int k = 0; k < 12; ++k) g.connectivity.set(k, ids[k]);
  g.offsets = {0, 4, 12};
  g.cell_types = {std::uint8_t(CellType::Tetra), std::uint8_t(CellType::Hexahedron)};
  g.point_fields.push_back({"temperature", 1, {}});
  for (int p = 0; p < 12; ++p) g.point_fields[0].values.push_back(0.25f * float(p) - 1.f);
  g.cell_fields.push_back({"velocity", 3, {1, 2, 3, -4, -5, -6}});
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
  }
  ASSERT_EQ(a.point_fields.size(), b.point_fields.size());
  for (std::size_t i = 0; i < a.point_fields.size(); ++i) {
    EXPECT_EQ(a.point_fields[i].name, b.point_fields[i].name);
    EXPECT_EQ(a.point_fields[i].values, b.point_fields[i].values);
  }
  ASSERT_EQ(a.cell_fields.size(), b.cell_fields.size());
  for (std::size_t i = 0; i < a.cell_fields.size(); ++i) {
    EXPECT_EQ(a.cell_fields[i].components, b.cell_fields[i].components);
    EXPECT_EQ(a.cell_fields[i].values, b.cell_fields[i].values);
  }
}

TEST(GridIo, RoundTripsMixedCellsThroughBothFormats) {
  for (bool wide : {false, true})
    for (const char* ext : {".vtu", ".vtk"}) {
      const UnstructuredGrid g = mixed_grid(wide);
      const std::string path = temp_path(std::string("mixed") + (wide ? "64" : "32") + ext);
      io::write_grid(g, path);
      EXPECT_TRUE(io::is_grid_file(path));
      const UnstructuredGrid back = io::read_grid(path);
      expect_same(g, back);
      std::filesystem::remove(path);
    }
}

TEST(GridIo, UniformTetsStayUniform) {
  UnstructuredGrid g;
  g.points = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
  g.connectivity = IndexArray::for_ids(5, 8);
  const std::uint64_t ids[] = {0, 1, 2, 3, 1, 2, 3, 4};
  for (int k = 0; k < 8; ++k) g.connectivity.set(k, ids[k]);
  const std::string path = temp_path("uniform.vtu");
  io::write_grid(g, path);
  const UnstructuredGrid back = io::read_grid(path);
  EXPECT_TRUE(back.uniform());
  EXPECT_EQ(back.uniform_type, CellType::Tetra);
  expect_same(g, back);
  std::filesystem::remove(path);
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
    EXPECT_EQ(g.points[3], 1.f);
    ASSERT_EQ(g.point_fields.size(), 1u);
    EXPECT_EQ(g.point_fields[0].name, "s");
    EXPECT_EQ(g.point_fields[0].values[3], 3.5f);
    std::filesystem::remove(path);
  }
}

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

TEST(GridIo, MalformedFilesAreRefusedByName) {
  const std::string head = "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  expect_input_error("poly.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n",
                     "POLYDATA");
  expect_input_error("trunc.vtk", head + "POINTS 4 float\n0 0 0 1 0 0\n", "file ends");
  expect_input_error("range.vtk", head + "POINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 9\nCELL_TYPES 1\n10\n",
                     "out of range");
  expect_input_error("cells.vtk", head + "POINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n7 0 1 2 3\nCELL_TYPES 1\n10\n",
                     "inconsistent");
  expect_input_error("types.vtk", head + "POINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 2\n10 10\n",
                     "CELL_TYPES");
  expect_input_error("bin.vtk", "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 100000000 float\n\1\2",
                     "file ends first");
  expect_input_error("huge.vtu", R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid><Piece NumberOfPoints="4000000000" NumberOfCells="0"><Points>
  <DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0</DataArray></Points></Piece>
  </UnstructuredGrid></VTKFile>)", "");
  expect_input_error("cellrange.vtu", R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid><Piece NumberOfPoints="3" NumberOfCells="1"><Points>
  <DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>
  <Cells><DataArray type="Int32" Name="connectivity" format="ascii">0 1 5</DataArray>
  <DataArray type="Int32" Name="offsets" format="ascii">3</DataArray>
  <DataArray type="UInt8" Name="types" format="ascii">5</DataArray></Cells></Piece>
  </UnstructuredGrid></VTKFile>)", "out of range");
}

TEST(GridIo, UnwritableOutputLeavesNothing) {
  const UnstructuredGrid g = mixed_grid(false);
  EXPECT_THROW(io::write_grid(g, "/nonexistent-dir/x.vtu"), InputError);
  EXPECT_THROW(io::write_grid(g, temp_path("x.abc")), InputError);
  EXPECT_FALSE(std::filesystem::exists("/nonexistent-dir/x.vtu"));
}

}  // namespace
