// point_cells: every point's incident corners, and each corner's cell,
// checked against a walk over the cells. A triangle mesh stores no cell per
// corner (cell_of computes it); a mesh with other polygons stores it.
#include "keymesh/analyze/incidence.hpp"

#include <gtest/gtest.h>

#include <vector>

using namespace keymesh;

namespace {

// The corners of point p, in increasing corner order, by walking the cells.
std::vector<std::uint32_t> corners_of(const SurfaceMesh& m, Id p) {
  std::vector<std::uint32_t> out;
  for (std::size_t k = 0; k < m.connectivity.size(); ++k)
    if (m.connectivity[k] == p) out.push_back(static_cast<std::uint32_t>(k));
  return out;
}

void expect_incidence_of_walk(const SurfaceMesh& m) {
  const analyze::PointCells pc = analyze::point_cells(m);
  for (Id c = 0; c < m.num_cells(); ++c)
    for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k)
      EXPECT_EQ(pc.cell_of(static_cast<std::uint32_t>(k)), c) << "corner " << k;
  for (Id p = 0; p < m.num_points(); ++p) {
    const auto expect = corners_of(m, p);
    ASSERT_EQ(pc.count(p), static_cast<Id>(expect.size())) << "point " << p;
    for (std::size_t i = 0; i < expect.size(); ++i) EXPECT_EQ(pc.corners[pc.offsets[p] + i], expect[i]);
  }
}

}  // namespace

TEST(Incidence, TrianglesStoreNoCellPerCorner) {
  SurfaceMesh m;  // an octahedron's upper half and a loose point (5 has no cell)
  m.points.assign(3 * 6, 0.0f);
  m.connectivity = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
  expect_incidence_of_walk(m);
  EXPECT_TRUE(analyze::point_cells(m).cell_of_corner.empty());
}

TEST(Incidence, PolygonsStoreTheirCells) {
  SurfaceMesh m;  // a quad, a triangle, a pentagon
  m.points.assign(3 * 7, 0.0f);
  m.connectivity = {0, 1, 2, 3, 1, 4, 2, 2, 4, 5, 6, 3};
  m.offsets = {0, 4, 7, 12};
  expect_incidence_of_walk(m);
  EXPECT_EQ(analyze::point_cells(m).cell_of_corner.size(), m.connectivity.size());
}
