// mesh/normals: the one face normal and KEY-REDUCE point normals.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "keymesh/mesh/normals.hpp"
#include "keymesh/parallel/threads.hpp"

namespace keymesh {
namespace {

// A regular tetrahedron's surface, outward-wound: each vertex's averaged
// normal is the direction from the centre to it (symmetry), and the
// area-weighted face normals of a closed surface sum to zero (divergence
// theorem).
SurfaceMesh tetrahedron() {
  SurfaceMesh m;
  m.points = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
  m.connectivity = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
  return m;
}

TEST(Normals, FaceNormalIsTwiceTheAreaAlongTheNormal) {
  // Right triangle with legs 2 and 3 in the xy plane: area 3, normal +z.
  const float P[] = {0, 0, 0, 2, 0, 0, 0, 3, 0};
  const PointIndex C[] = {0, 1, 2};
  const Vec3f n = triangle_normal(P, C, 0);
  EXPECT_EQ(n.x, 0.0f);
  EXPECT_EQ(n.y, 0.0f);
  EXPECT_EQ(n.z, 6.0f);
}

TEST(Normals, ClosedSurfaceFaceNormalsSumToZeroAndVertexNormalsPointOutward) {
  SurfaceMesh m = tetrahedron();
  Vec3f total{0, 0, 0};
  for (const Vec3f& f : face_normals(m)) total = add(total, f);
  EXPECT_NEAR(total.x, 0, 1e-6);
  EXPECT_NEAR(total.y, 0, 1e-6);
  EXPECT_NEAR(total.z, 0, 1e-6);
  average_normals(m);
  const Field* n = m.find_point_field("Normals");
  ASSERT_NE(n, nullptr);
  for (Id p = 0; p < 4; ++p)
    for (int a = 0; a < 3; ++a)
      EXPECT_NEAR(n->values[3 * p + a], m.points[3 * p + a] / std::sqrt(3.0f), 1e-6) << p << " " << a;
}

TEST(Normals, SumsEqualASerialScatterInTriangleOrderAtAnyThreadCount) {
  // A strip of 200 random-ish triangles over 60 points, one unused point.
  SurfaceMesh m;
  for (int i = 0; i < 61; ++i)
    m.points.insert(m.points.end(), {std::sin(1.3f * i), std::cos(0.7f * i), 0.01f * float(i * i % 17)});
  for (int t = 0; t < 200; ++t)
    m.connectivity.insert(m.connectivity.end(), {PointIndex(t * 7 % 60), PointIndex((t * 13 + 1) % 60),
                                                 PointIndex((t * 29 + 2) % 60)});
  std::vector<Vec3f> serial(61, Vec3f{0, 0, 0});
  for (Id t = 0; t < m.num_cells(); ++t) {
    const Vec3f f = triangle_normal(m.points.data(), m.connectivity.data(), t);
    for (int k = 0; k < 3; ++k) serial[m.connectivity[3 * t + k]] = add(serial[m.connectivity[3 * t + k]], f);
  }
  for (int threads : {1, 2, 4}) {
    parallel::set_thread_count(threads);
    const std::vector<Vec3f> sums = point_normal_sums(m);
    ASSERT_EQ(sums.size(), serial.size());
    for (std::size_t p = 0; p < sums.size(); ++p) {
      EXPECT_EQ(std::memcmp(&sums[p], &serial[p], sizeof(Vec3f)), 0) << "point " << p << " threads " << threads;
    }
  }
  parallel::set_thread_count(0);
}

}  // namespace
}  // namespace keymesh
