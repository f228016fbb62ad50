#include "keymesh/generate/unstructured/tetrahedralize.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/threads.hpp"

using namespace keymesh;
using generate::tet_volume;
using generate::tetrahedralize5;

namespace {

ImageGrid ramp_grid(std::array<Id, 3> dims, std::array<double, 3> spacing, std::array<double, 3> origin) {
  ImageGrid g;
  g.allocate(dims, ScalarType::Int16);
  g.spacing = spacing;
  g.origin = origin;
  auto* v = reinterpret_cast<std::int16_t*>(g.data());
  for (Id p = 0; p < g.num_points(); ++p) v[p] = static_cast<std::int16_t>(p % 1000 - 500);
  return g;
}

// How many tets use every triangular face (by sorted point ids).
std::map<std::array<std::uint64_t, 3>, int> face_use(const UnstructuredGrid& g) {
  std::map<std::array<std::uint64_t, 3>, int> use;
  for (Id t = 0; t < g.num_cells(); ++t) {
    const std::uint64_t b = g.cell_begin(t);
    for (int skip = 0; skip < 4; ++skip) {
      std::array<std::uint64_t, 3> f{};
      int k = 0;
      for (int v = 0; v < 4; ++v)
        if (v != skip) f[k++] = g.connectivity[b + v];
      std::sort(f.begin(), f.end());
      ++use[f];
    }
  }
  return use;
}

// Checks a tet mesh is a conforming, positively oriented filling of a box:
// all volumes positive, summing to the box volume, every face used once
// (on the boundary) or twice (inside), and `boundary_faces` on the boundary.
void expect_conforming_box(const UnstructuredGrid& g, double box_volume, Id boundary_faces) {
  double sum = 0;
  const float* P = g.points.data();
  for (Id t = 0; t < g.num_cells(); ++t) {
    const std::uint64_t b = g.cell_begin(t);
    const double v = tet_volume(P + 3 * g.connectivity[b], P + 3 * g.connectivity[b + 1],
                                P + 3 * g.connectivity[b + 2], P + 3 * g.connectivity[b + 3]);
    ASSERT_GT(v, 0) << "tet " << t;
    sum += v;
  }
  EXPECT_NEAR(sum, box_volume, 1e-9 * box_volume);
  Id once = 0;
  for (const auto& [face, n] : face_use(g)) {
    ASSERT_LE(n, 2);
    once += n == 1;
  }
  EXPECT_EQ(once, boundary_faces);
}

// Two triangles per boundary quad of an a x b x c voxel box.
Id box_boundary_triangles(Id a, Id b, Id c) { return 2 * 2 * (a * b + b * c + a * c); }

TEST(Tetrahedralize5, VoxelGridCountsVolumesAndConformity) {
  for (auto dims : {std::array<Id, 3>{2, 2, 2}, std::array<Id, 3>{5, 5, 5}, std::array<Id, 3>{4, 6, 3}}) {
    const ImageGrid grid = ramp_grid(dims, {0.5, 2.0, 1.25}, {-3, 1, 7});
    const UnstructuredGrid g = tetrahedralize5(grid);
    const Id voxels = (dims[0] - 1) * (dims[1] - 1) * (dims[2] - 1);
    EXPECT_EQ(g.num_points(), dims[0] * dims[1] * dims[2]);
    EXPECT_EQ(g.num_cells(), 5 * voxels);
    EXPECT_FALSE(g.connectivity.wide());
    EXPECT_NO_THROW(g.validate("grid"));
    const double box = (dims[0] - 1) * 0.5 * (dims[1] - 1) * 2.0 * (dims[2] - 1) * 1.25;
    expect_conforming_box(g, box, box_boundary_triangles(dims[0] - 1, dims[1] - 1, dims[2] - 1));
    // Points and the carried scalars.
    const Field* f = g.find_point_field(grid.name);
    ASSERT_NE(f, nullptr);
    const auto* v = reinterpret_cast<const std::int16_t*>(grid.data());
    for (Id p = 0; p < g.num_points(); ++p) ASSERT_EQ(f->values[p], float(v[p]));
    const Id last = g.num_points() - 1;
    EXPECT_FLOAT_EQ(g.points[3 * last], float(-3 + 0.5 * (dims[0] - 1)));
    EXPECT_FLOAT_EQ(g.points[3 * last + 2], float(7 + 1.25 * (dims[2] - 1)));
  }
}

TEST(Tetrahedralize5, MirroredGridStaysPositive) {
  const ImageGrid grid = ramp_grid({4, 4, 4}, {1.0, -1.0, 1.0}, {0, 0, 0});
  const UnstructuredGrid g = tetrahedralize5(grid);
  expect_conforming_box(g, 27.0, box_boundary_triangles(3, 3, 3));
}

TEST(Tetrahedralize5, SameAtAnyThreadCount) {
  const ImageGrid grid = ramp_grid({17, 9, 11}, {1, 1, 1}, {0, 0, 0});
  parallel::set_thread_count(1);
  const UnstructuredGrid a = tetrahedralize5(grid);
  parallel::set_thread_count(4);
  const UnstructuredGrid b = tetrahedralize5(grid);
  parallel::set_thread_count(0);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.connectivity.narrow(), b.connectivity.narrow());
}

// An unstructured hexahedral grid of a x b x c unit cells, VTK_HEXAHEDRON
// corner order, point ids shuffled with `seed` (in grid order when 0).
UnstructuredGrid hex_box(Id a, Id b, Id c, unsigned seed) {
  const Id nx = a + 1, ny = b + 1, nz = c + 1, n = nx * ny * nz;
  std::vector<std::uint64_t> perm(n);
  std::iota(perm.begin(), perm.end(), 0);
  if (seed) std::shuffle(perm.begin(), perm.end(), std::mt19937(seed));
  UnstructuredGrid g;
  g.points.resize(3 * n);
  Field temp{"temperature", 1, Array<float>(n, 0.f)};
  for (Id k = 0; k < nz; ++k)
    for (Id j = 0; j < ny; ++j)
      for (Id i = 0; i < nx; ++i) {
        const std::uint64_t p = perm[i + nx * (j + ny * k)];
        g.points[3 * p] = float(i), g.points[3 * p + 1] = float(j), g.points[3 * p + 2] = float(k);
        temp.values[p] = float(i + 10 * j + 100 * k);
      }
  g.point_fields.push_back(temp);
  g.uniform_type = CellType::Hexahedron;
  g.connectivity = IndexArray::for_ids(n, 8 * a * b * c);
  Field id{"cell_id", 1, {}};
  std::size_t w = 0;
  const int hex[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (Id k = 0; k < c; ++k)
    for (Id j = 0; j < b; ++j)
      for (Id i = 0; i < a; ++i) {
        for (const auto& d : hex) g.connectivity.set(w++, perm[(i + d[0]) + nx * ((j + d[1]) + ny * (k + d[2]))]);
        id.values.push_back(float(id.values.size()));
      }
  g.cell_fields.push_back(id);
  return g;
}

TEST(Tetrahedralize5, HexGridWithShuffledIds) {
  for (unsigned seed : {0u, 3u}) {
    const UnstructuredGrid hexes = hex_box(4, 3, 5, seed);
    const UnstructuredGrid g = tetrahedralize5(hexes);
    EXPECT_EQ(g.num_cells(), 5 * 4 * 3 * 5);
    EXPECT_EQ(g.points, hexes.points);
    expect_conforming_box(g, 60.0, box_boundary_triangles(4, 3, 5));
    const Field* id = g.find_cell_field("cell_id");
    ASSERT_NE(id, nullptr);
    for (Id t = 0; t < g.num_cells(); ++t) ASSERT_EQ(id->values[t], float(t / 5));
  }
}

// A ring of `cells` hexahedra around a hole, each sharing a face with the next.
UnstructuredGrid hex_ring(int cells) {
  UnstructuredGrid g;
  const double pi = std::acos(-1.0);
  for (int z = 0; z < 2; ++z)
    for (int i = 0; i < cells; ++i)
      for (double r : {1.0, 2.0}) {
        const double a = 2 * pi * i / cells;
        g.points.insert(g.points.end(), {float(r * std::cos(a)), float(r * std::sin(a)), float(z)});
      }
  auto id = [&](int i, int outer, int z) { return std::uint64_t(2 * ((i % cells) + cells * z) + outer); };
  g.uniform_type = CellType::Hexahedron;
  g.connectivity = IndexArray::for_ids(g.points.size() / 3, 8 * std::size_t(cells));
  std::size_t w = 0;
  for (int i = 0; i < cells; ++i)
    for (int z = 0; z < 2; ++z) {
      // Bottom face counter-clockwise seen from +z, then the top face.
      g.connectivity.set(w++, id(i, 0, z));
      g.connectivity.set(w++, id(i, 1, z));
      g.connectivity.set(w++, id(i + 1, 1, z));
      g.connectivity.set(w++, id(i + 1, 0, z));
    }
  return g;
}

TEST(Tetrahedralize5, EvenRingSplitsOddRingIsRefused) {
  // A ring of an even number of cells 2-colours; an odd one cannot.
  const UnstructuredGrid even = hex_ring(6);
  const UnstructuredGrid g = tetrahedralize5(even);
  EXPECT_EQ(g.num_cells(), 30);
  for (const auto& [face, n] : face_use(g)) ASSERT_LE(n, 2);
  try {
    tetrahedralize5(hex_ring(5));
    FAIL() << "an odd ring of hexahedra must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("matching diagonals"), std::string::npos) << e.what();
  }
}

TEST(Tetrahedralize24, VoxelGridCountsVolumesConformityAndFields) {
  for (auto dims : {std::array<Id, 3>{2, 2, 2}, std::array<Id, 3>{5, 5, 5}, std::array<Id, 3>{4, 6, 3}}) {
    for (bool weld : {false, true}) {
      const ImageGrid grid = ramp_grid(dims, {0.5, 2.0, 1.25}, {-3, 1, 7});
      const UnstructuredGrid g = generate::tetrahedralize24(grid, weld);
      const Id a = dims[0] - 1, b = dims[1] - 1, c = dims[2] - 1;
      // Corners, one centre per distinct voxel face (counted per axis), one per voxel.
      const Id faces = dims[0] * b * c + a * dims[1] * c + a * b * dims[2];
      EXPECT_EQ(g.num_points(), dims[0] * dims[1] * dims[2] + faces + a * b * c);
      EXPECT_EQ(g.num_cells(), 24 * a * b * c);
      const double box = a * 0.5 * b * 2.0 * c * 1.25;
      // Every boundary quad is cut into 4 triangles from its centre.
      expect_conforming_box(g, box, 4 * (a * b + b * c + a * c) * 2);
      // The carried scalar at a cell centre is the mean of its 8 corners.
      const Field* f = g.find_point_field(grid.name);
      ASSERT_NE(f, nullptr);
      const auto* v = reinterpret_cast<const std::int16_t*>(grid.data());
      double mean = 0;
      for (int k = 0; k < 8; ++k) mean += v[(k & 1) + dims[0] * ((k >> 1) & 1) + dims[0] * dims[1] * ((k >> 2) & 1)];
      EXPECT_FLOAT_EQ(f->values[g.num_points() - a * b * c], float(mean / 8));
    }
  }
  const ImageGrid n4 = ramp_grid({4, 4, 4}, {1, 1, 1}, {0, 0, 0});
  EXPECT_EQ(generate::tetrahedralize24(n4).num_points(), 64 + 3 * 4 * 9 + 27);  // N^3 + 3N(N-1)^2 + (N-1)^3
}

TEST(Tetrahedralize24, HexGridMatchesTheVoxelGrid) {
  for (unsigned seed : {0u, 5u}) {
    const UnstructuredGrid hexes = hex_box(3, 4, 2, seed);
    for (bool weld : {false, true}) {
      const UnstructuredGrid g = generate::tetrahedralize24(hexes, weld);
      EXPECT_EQ(g.num_cells(), 24 * 24);
      EXPECT_EQ(g.num_points(), 4 * 5 * 3 + (4 * 4 * 2 + 3 * 5 * 2 + 3 * 4 * 3) + 24);
      expect_conforming_box(g, 24.0, 8 * (12 + 8 + 6));
      const Field* id = g.find_cell_field("cell_id");
      ASSERT_NE(id, nullptr);
      for (Id t = 0; t < g.num_cells(); ++t) ASSERT_EQ(id->values[t], float(t / 24));
    }
  }
}

TEST(Tetrahedralize5, RefusesNonHexCellsAndBadGrids) {
  UnstructuredGrid g = hex_box(1, 1, 1, 0);
  g.uniform_type = CellType::Tetra;  // 8 ids read as two tets
  EXPECT_THROW(tetrahedralize5(g), InputError);
  ImageGrid flat = ramp_grid({4, 1, 4}, {1, 1, 1}, {0, 0, 0});
  EXPECT_THROW(tetrahedralize5(flat), InputError);
}

}  // namespace
