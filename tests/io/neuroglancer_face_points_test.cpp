// The writer's settling of face points (io/neuroglancer/face_points.hpp): a
// candidate point lying in a node face plane that ends no boundary edge in
// that plane moves two quantization steps into the node along that axis
// only; a point that ends such an edge, a point not marked as a candidate and
// an unused point stay where they are, and the triangles never change.
#include "io/neuroglancer/face_points.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

using namespace keymesh::io::neuroglancer;

namespace {

constexpr int kBits = 4;  // node faces at 0 and 15

// A closed tetrahedron (every edge paired: no boundary edge at all) whose
// point 0 lies on the low x face, point 1 on the high y face and point 2 on
// the corner of the low x and low z faces; point 3 is inside. Point 4 is on
// the low x face but in no triangle.
QuantizedMesh closed_tetrahedron() {
  QuantizedMesh m;
  m.positions = {0, 7, 7,  7, 15, 7,  0, 5, 0,  8, 6, 9,  0, 3, 3};
  m.triangles = {0, 1, 2,  0, 3, 1,  1, 3, 2,  2, 3, 0};
  return m;
}

}  // namespace

TEST(NeuroglancerFacePoints, PointsWithoutBoundaryEdgeMoveIntoTheNode) {
  QuantizedMesh m = closed_tetrahedron();
  const QuantizedMesh before = m;
  EXPECT_EQ(settle_face_points(m, kBits, std::vector<std::uint8_t>(5, 1)), 3);
  const std::vector<std::int32_t> expected = {2, 7, 7,  7, 13, 7,  2, 5, 2,  8, 6, 9,  0, 3, 3};
  EXPECT_EQ(m.positions, expected);  // low faces +2, high face -2, the corner on both axes, unused 4 stays
  EXPECT_EQ(m.triangles, before.triangles);
}

TEST(NeuroglancerFacePoints, OnlyCandidatesMove) {
  QuantizedMesh m = closed_tetrahedron();
  std::vector<std::uint8_t> candidates(5, 0);
  candidates[1] = 1;
  EXPECT_EQ(settle_face_points(m, kBits, candidates), 1);
  QuantizedMesh expected = closed_tetrahedron();
  expected.positions[3 * 1 + 1] = 13;
  EXPECT_EQ(m.positions, expected.positions);
  QuantizedMesh untouched = closed_tetrahedron();
  EXPECT_EQ(settle_face_points(untouched, kBits, {}), 0);  // no merge ran: nothing to settle
  EXPECT_EQ(untouched.positions, closed_tetrahedron().positions);
}

TEST(NeuroglancerFacePoints, EndsOfABoundaryEdgeInTheFaceStay) {
  // An open piece: triangles (0, 1, 2), (0, 2, 3) with the edges 0-1 and 3-0
  // in the low x face left unpaired (the cut the neighbouring node shares).
  // Point 0 ends them and stays; point 1 also ends 0-1 and stays; point 3
  // ends 3-0; none moves. Point 2 is inside.
  QuantizedMesh m;
  m.positions = {0, 4, 4,  0, 9, 4,  6, 6, 6,  0, 4, 10};
  m.triangles = {0, 1, 2,  0, 2, 3};
  const QuantizedMesh before = m;
  EXPECT_EQ(settle_face_points(m, kBits, std::vector<std::uint8_t>(4, 1)), 0);
  EXPECT_EQ(m.positions, before.positions);
}

TEST(NeuroglancerFacePoints, ABoundaryEdgeHoldsOnlyItsOwnFace) {
  // Point 0 is on the low x face and the low y face; its boundary edge 0-1
  // lies in the low x face only (1 is not on the low y face): it stays in x
  // and moves into the node in y.
  QuantizedMesh m;
  m.positions = {0, 0, 4,  0, 9, 4,  6, 6, 6};
  m.triangles = {0, 1, 2};
  EXPECT_EQ(settle_face_points(m, kBits, std::vector<std::uint8_t>(3, 1)), 1);
  const std::vector<std::int32_t> expected = {0, 2, 4,  0, 9, 4,  6, 6, 6};
  EXPECT_EQ(m.positions, expected);
}
