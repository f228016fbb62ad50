// mesh/unit_normals: every normal a unit vector, undefined ones from their
// neighbours, by hand-checkable strips.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "keymesh/mesh/face_normal.hpp"
#include "keymesh/mesh/unit_normals.hpp"

namespace keymesh {
namespace {

// A strip of triangles along x in the plane z = 0: points 0..2k-1, point
// 2i at (i, 0, 0) and 2i + 1 at (i, 1, 0); triangles (2i, 2i+2, 2i+1) and
// (2i+1, 2i+2, 2i+3), all wound to +z. Normals start as +z everywhere.
SurfaceMesh strip(int columns) {
  SurfaceMesh m;
  for (int i = 0; i < columns; ++i) m.points.insert(m.points.end(), {float(i), 0, 0, float(i), 1, 0});
  for (PointIndex i = 0; i + 1 < PointIndex(columns); ++i)
    m.connectivity.insert(m.connectivity.end(), {2 * i, 2 * i + 2, 2 * i + 1, 2 * i + 1, 2 * i + 2, 2 * i + 3});
  m.point_fields.push_back(Field{"Normals", 3, Array<float>(m.points.size(), 0.0f)});
  for (Id p = 0; p < m.num_points(); ++p) m.point_fields[0].values[3 * p + 2] = 1;
  return m;
}

Vec3f normal_at(const SurfaceMesh& m, Id p) {
  const float* v = m.point_fields[0].values.data() + 3 * p;
  return Vec3f{v[0], v[1], v[2]};
}

TEST(Normals, UnitNormalsKeepUnitOnesAndScaleTheOthers) {
  SurfaceMesh m = strip(3);
  float* v = m.point_fields[0].values.data();
  const float tilted[3] = {0.6f, 0.0f, 0.8f};  // unit, not +z: kept as it is
  std::copy_n(tilted, 3, v + 3);
  v[6] = 0, v[7] = -2.5f, v[8] = 0;         // non-unit: scaled
  v[9] = 1e-30f, v[10] = 0, v[11] = 0;       // tiny (its float square underflows): still scaled
  EXPECT_EQ(make_unit_normals(m, v), 2);
  EXPECT_EQ(std::memcmp(v + 3, tilted, sizeof tilted), 0);
  EXPECT_EQ(normal_at(m, 2).y, -1.0f);
  EXPECT_EQ(normal_at(m, 3).x, 1.0f);
  SurfaceMesh unchanged = strip(3);
  EXPECT_EQ(make_unit_normals(unchanged, unchanged.point_fields[0].values.data()), 0);
}

TEST(Normals, UndefinedNormalsTakeTheirNeighboursRingByRing) {
  // Columns 1..3 undefined (zero, NaN, infinity): column 1 takes column
  // 0's tilted normals, column 3 column 4's +z, column 2 (no defined
  // neighbour at first) the next round's sum of both.
  SurfaceMesh m = strip(5);
  float* v = m.point_fields[0].values.data();
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (Id p : {0, 1}) v[3 * p] = 0.6f, v[3 * p + 1] = 0, v[3 * p + 2] = 0.8f;
  const float bad[6][3] = {{0, 0, 0}, {0, 0, 0}, {nan, 0, 0}, {0, inf, 0}, {0, 0, -0.0f}, {nan, nan, nan}};
  for (Id p = 2; p < 8; ++p) std::copy_n(bad[p - 2], 3, v + 3 * p);
  EXPECT_EQ(make_unit_normals(m, v), 6);
  for (Id p = 0; p < m.num_points(); ++p) {
    const Vec3f n = normal_at(m, p);
    EXPECT_NEAR(std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z), 1.0, 1e-6) << p;
    EXPECT_EQ(n.y, 0.0f) << p;
  }
  EXPECT_NEAR(normal_at(m, 2).x, 0.6f, 1e-6);  // only column 0 is a defined neighbour
  EXPECT_NEAR(normal_at(m, 7).x, 0.0f, 1e-6);  // only column 4 (+z)
  EXPECT_GT(normal_at(m, 4).x, 0.0f);          // between the two
  EXPECT_LT(normal_at(m, 4).x, 0.6f);
}

TEST(Normals, UnitNormalsWithoutAnyDefinedOneArePlusZ) {
  // Two triangles in separate components: the first all zero, the second
  // defined; and a point in no cell.
  SurfaceMesh m;
  m.points = {0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 5, 5, 5};
  m.connectivity = {0, 1, 2, 3, 4, 5};
  m.point_fields.push_back(Field{"Normals", 3, Array<float>(21, 0.0f)});
  float* v = m.point_fields[0].values.data();
  for (Id p = 3; p < 6; ++p) v[3 * p] = 1;
  EXPECT_EQ(make_unit_normals(m, v), 4);
  for (Id p : {0, 1, 2, 6}) {
    const Vec3f n = normal_at(m, p);
    EXPECT_EQ(n.x, 0.0f) << p;
    EXPECT_EQ(n.y, 0.0f) << p;
    EXPECT_EQ(n.z, 1.0f) << p;
  }
  EXPECT_EQ(normal_at(m, 4).x, 1.0f);
}

}  // namespace
}  // namespace keymesh
