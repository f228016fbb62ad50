// mesh/normals: the one face normal and KEY-REDUCE point normals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

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

// The serial scatter the sums are defined by: every triangle's normal added
// to its three points in triangle order, from +0.
std::vector<Vec3f> serial_sums(const SurfaceMesh& m) {
  std::vector<Vec3f> serial(static_cast<std::size_t>(m.num_points()), Vec3f{0, 0, 0});
  for (Id t = 0; t < m.num_cells(); ++t) {
    const Vec3f f = triangle_normal(m.points.data(), m.connectivity.data(), t);
    for (int k = 0; k < 3; ++k) serial[m.connectivity[3 * t + k]] = add(serial[m.connectivity[3 * t + k]], f);
  }
  return serial;
}

TEST(Normals, ChunkedSumsKeepTheSerialOrderOnLargeMeshesInAnyTriangleOrder) {
  // A grid of quads, two triangles each, in row order (a contour's
  // locality: points shared across the chunks' cuts), then the same
  // triangles shuffled (most corners set aside), with unused points,
  // degenerate triangles naming a point twice, and zero-area ones whose
  // normals hold -0 components (+0 + -0 is +0: the sum must start from +0).
  const int n = 180;
  SurfaceMesh m;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      m.points.insert(m.points.end(), {float(i) + 0.3f * std::sin(0.37f * float(i * j)), float(j),
                                       0.5f * std::cos(0.11f * float(i + 3 * j))});
  m.points.insert(m.points.end(), {7, 7, 7, 8, 8, 8});  // unused
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const auto a = PointIndex(j * n + i), b = a + 1, c = a + PointIndex(n), d = c + 1;
      m.connectivity.insert(m.connectivity.end(), {a, b, d, a, d, c});
      if ((i + j) % 97 == 0) m.connectivity.insert(m.connectivity.end(), {a, b, a});
      if ((i * j) % 89 == 1) m.connectivity.insert(m.connectivity.end(), {b, b, b});
    }
  ASSERT_GT(m.num_cells(), 60000);
  for (int shuffled = 0; shuffled < 2; ++shuffled) {
    if (shuffled) {
      std::vector<Id> order(static_cast<std::size_t>(m.num_cells()));
      std::iota(order.begin(), order.end(), Id{0});
      std::shuffle(order.begin(), order.end(), std::mt19937(5));
      Array<PointIndex> c(m.connectivity.size());
      for (std::size_t t = 0; t < order.size(); ++t)
        std::copy_n(m.connectivity.begin() + 3 * order[t], 3, c.begin() + 3 * static_cast<Id>(t));
      m.connectivity = std::move(c);
    }
    const std::vector<Vec3f> serial = serial_sums(m);
    for (int threads : {1, 2, 3, 4}) {
      parallel::set_thread_count(threads);
      const std::vector<Vec3f> sums = point_normal_sums(m);
      ASSERT_EQ(sums.size(), serial.size());
      std::size_t differ = 0;
      for (std::size_t p = 0; p < sums.size(); ++p) differ += std::memcmp(&sums[p], &serial[p], sizeof(Vec3f)) != 0;
      EXPECT_EQ(differ, 0u) << "threads " << threads << " shuffled " << shuffled;
      SurfaceMesh averaged = m;
      average_normals(averaged);
      const Field* f = averaged.find_point_field("Normals");
      ASSERT_NE(f, nullptr);
      differ = 0;
      for (std::size_t p = 0; p < sums.size(); ++p) {
        const Vec3f u = unit(serial[p]);
        differ += std::memcmp(&u, f->values.data() + 3 * p, sizeof(Vec3f)) != 0;
      }
      EXPECT_EQ(differ, 0u) << "average_normals, threads " << threads << " shuffled " << shuffled;
    }
  }
  parallel::set_thread_count(0);
}

}  // namespace
}  // namespace keymesh
