// The writer's flip of triangles on three collinear corners
// (io/neuroglancer/collinear_triangles.hpp): each goes with its neighbour
// across the long side, no zero-area triangle is left, the pair tiles the
// neighbour (same area, same orientation), the directed edges left unpaired
// stay the same, and a line with no neighbour stays.
#include "io/neuroglancer/collinear_triangles.hpp"

#include <gtest/gtest.h>

#include <array>
#include <map>

using namespace keymesh::io::neuroglancer;

namespace {

std::map<std::pair<std::uint32_t, std::uint32_t>, int> unpaired(const QuantizedMesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> net;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t a = m.triangles[t + c], b = m.triangles[t + (c + 1) % 3];
      net[{std::min(a, b), std::max(a, b)}] += a < b ? 1 : -1;
    }
  std::erase_if(net, [](const auto& e) { return e.second == 0; });
  return net;
}

// Twice the signed area vector of triangle t.
std::array<std::int64_t, 3> area2(const QuantizedMesh& m, std::size_t t) {
  std::array<std::int64_t, 3> p[3];
  for (int c = 0; c < 3; ++c)
    for (int a = 0; a < 3; ++a) p[c][a] = m.positions[3 * m.triangles[3 * t + c] + a];
  std::array<std::int64_t, 3> u{}, v{};
  for (int a = 0; a < 3; ++a) u[a] = p[1][a] - p[0][a], v[a] = p[2][a] - p[0][a];
  return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}

// In the plane z = 3: a (0, 8), b (4, 8), c (10, 8) on one line, d (5, 16)
// above it, e (5, 0) below. The line (a, b, c), its neighbour (a, c, d)
// across the long side a-c, and (b, a, e), (c, b, e) across its short sides.
QuantizedMesh line_and_neighbours() {
  QuantizedMesh m;
  m.positions = {0, 8, 3, 4, 8, 3, 10, 8, 3, 5, 16, 3, 5, 0, 3};
  m.triangles = {0, 1, 2,  0, 2, 3,  1, 0, 4,  2, 1, 4};
  return m;
}

}  // namespace

TEST(NeuroglancerCollinearTriangles, LineFlipsWithItsNeighbour) {
  QuantizedMesh m = line_and_neighbours();
  const auto before_unpaired = unpaired(m);
  const auto neighbour = area2(m, 1);
  EXPECT_EQ(area2(m, 0), (std::array<std::int64_t, 3>{0, 0, 0}));
  EXPECT_EQ(flip_collinear_triangles(m), 1);
  EXPECT_EQ(m.triangles.size(), 12u);
  EXPECT_EQ(unpaired(m), before_unpaired);
  std::array<std::int64_t, 3> sum{};
  for (std::size_t t = 0; t < 2; ++t) {
    const auto s = area2(m, t);
    EXPECT_GT(s[2] * neighbour[2], 0) << "triangle " << t;  // same orientation, not zero
    for (int a = 0; a < 3; ++a) sum[a] += s[a];
  }
  EXPECT_EQ(sum, neighbour);  // the two tile the neighbour
  EXPECT_EQ(m.positions, line_and_neighbours().positions);
}

TEST(NeuroglancerCollinearTriangles, LineWithoutNeighbourStays) {
  QuantizedMesh m = line_and_neighbours();
  m.triangles.erase(m.triangles.begin() + 3, m.triangles.begin() + 6);  // no triangle across a-c
  const QuantizedMesh before = m;
  EXPECT_EQ(flip_collinear_triangles(m), 0);
  EXPECT_EQ(m.triangles, before.triangles);
}

TEST(NeuroglancerCollinearTriangles, NoFlipOntoATriangleThereAlready) {
  QuantizedMesh m = line_and_neighbours();
  m.triangles.insert(m.triangles.end(), {3, 1, 0});  // (d, b, a): the flip's (a, b, d) reversed
  const QuantizedMesh before = m;
  EXPECT_EQ(flip_collinear_triangles(m), 0);
  EXPECT_EQ(m.triangles, before.triangles);
}
