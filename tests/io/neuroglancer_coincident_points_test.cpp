// The writer's merge of points that quantization puts on one integer point
// (io/neuroglancer/coincident_points.hpp): collapsed triangles dropped,
// opposite triangles on the same points cancelled, a closed 2-cycle stays
// closed, and a mesh with no such points is left as it was.
#include "io/neuroglancer/coincident_points.hpp"

#include <gtest/gtest.h>

#include <array>
#include <map>
#include <set>

using namespace keymesh::io::neuroglancer;

namespace {

// Net count of every directed edge minus its reverse: all zero for a closed 2-cycle.
bool closed(const QuantizedMesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> net;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t a = m.triangles[t + c], b = m.triangles[t + (c + 1) % 3];
      net[{std::min(a, b), std::max(a, b)}] += a < b ? 1 : -1;
    }
  for (const auto& [edge, n] : net)
    if (n != 0) return false;
  return true;
}

std::array<std::int32_t, 3> at(const QuantizedMesh& m, std::uint32_t i) {
  return {m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]};
}

// A closed octahedron around (100, 100, 100) whose +x tip is split into two
// points 1 apart along y (a sliver pair), both on the same integer point
// when `coincident`.
QuantizedMesh split_octahedron(bool coincident) {
  QuantizedMesh m;
  m.positions = {200, 100, 100,  0, 100, 100,  100, 200, 100,  100, 0, 100,  100, 100, 200,  100, 100, 0,
                 200, coincident ? 100 : 101, 100};
  // Points: 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z, 6 the +x tip's twin. The +x
  // side's four triangles use 0 or 6, and two slivers (0, 6, z) close the gap.
  m.triangles = {0, 2, 4,  6, 4, 3,  0, 5, 2,  6, 3, 5,  1, 4, 2,  1, 3, 4,  1, 2, 5,  1, 5, 3,
                 0, 4, 6,  0, 6, 5};
  return m;
}

}  // namespace

TEST(NeuroglancerCoincidentPoints, SplitTipMergesAndStaysClosed) {
  QuantizedMesh m = split_octahedron(true);
  ASSERT_TRUE(closed(m));
  merge_coincident_points(m);
  EXPECT_EQ(m.positions.size(), 18u);   // 6 points: the twin merged into the tip
  EXPECT_EQ(m.triangles.size(), 24u);   // the two slivers collapsed
  EXPECT_TRUE(closed(m));
  std::set<std::array<std::int32_t, 3>> distinct;
  for (std::uint32_t i = 0; i < 6; ++i) distinct.insert(at(m, i));
  EXPECT_EQ(distinct.size(), 6u);
  for (std::size_t t = 0; t < m.triangles.size(); t += 3) {
    EXPECT_NE(m.triangles[t], m.triangles[t + 1]);
    EXPECT_NE(m.triangles[t + 1], m.triangles[t + 2]);
    EXPECT_NE(m.triangles[t], m.triangles[t + 2]);
  }
}

TEST(NeuroglancerCoincidentPoints, OppositeTrianglesCancel) {
  // Two triangles on points that merge into the same three, opposite: none stay.
  QuantizedMesh m;
  m.positions = {0, 0, 0, 10, 0, 0, 0, 10, 0, 0, 0, 0};
  m.triangles = {0, 1, 2, 3, 2, 1};
  merge_coincident_points(m);
  EXPECT_TRUE(m.triangles.empty());
  EXPECT_TRUE(m.positions.empty());
  // Three on one set, net +1: the first of the winning side stays.
  m.positions = {0, 0, 0, 10, 0, 0, 0, 10, 0, 0, 0, 0};
  m.triangles = {3, 2, 1, 0, 1, 2, 1, 2, 3};
  merge_coincident_points(m);
  EXPECT_EQ(m.triangles, (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(m.positions.size(), 9u);
}

TEST(NeuroglancerCoincidentPoints, DistinctPointsUnchanged) {
  const QuantizedMesh before = split_octahedron(false);
  QuantizedMesh m = before;
  merge_coincident_points(m);
  EXPECT_EQ(m.positions, before.positions);
  EXPECT_EQ(m.triangles, before.triangles);
}

TEST(NeuroglancerCoincidentPoints, ManyPointsMergeIntoTheirFirst) {
  // 2001 distinct lattice points in strips of triangles, then three twins of
  // earlier points (5, 700, 1999), each in a triangle of its own: every twin
  // becomes its first point, the others keep their numbers.
  QuantizedMesh m;
  const std::uint32_t n = 2001;
  for (std::uint32_t i = 0; i < n; ++i)
    m.positions.insert(m.positions.end(), {std::int32_t(i % 20 * 3), std::int32_t(i / 20 % 20 * 5), std::int32_t(i / 400 * 7)});
  for (std::uint32_t i = 0; i + 2 < n; i += 3) m.triangles.insert(m.triangles.end(), {i, i + 1, i + 2});
  QuantizedMesh expected = m;
  const std::uint32_t twins[3] = {5, 700, 1999};
  for (std::uint32_t j = 0; j < 3; ++j) {
    const std::uint32_t k = twins[j];
    m.positions.insert(m.positions.end(), m.positions.begin() + 3 * k, m.positions.begin() + 3 * k + 3);
    m.triangles.insert(m.triangles.end(), {n + j, 1000 + j, 1500 + j});
    expected.triangles.insert(expected.triangles.end(), {k, 1000 + j, 1500 + j});
  }
  merge_coincident_points(m);
  EXPECT_EQ(m.positions, expected.positions);
  EXPECT_EQ(m.triangles, expected.triangles);
}
