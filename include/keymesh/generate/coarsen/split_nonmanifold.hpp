#pragma once
// Non-manifold points and edges of a coarsened surface, undone from its
// topology alone (the triangles' point ids; no coordinate is compared).
//
// Coarsening (coarsen.hpp) merges every crossing into the grid point nearest
// it. Where two sheets of the fine surface pass within a voxel of one grid
// point, both sheets' crossings merge into that point: two cones meet at it
// (a point with two fans), or two sheets share a coarse edge (an edge with
// four triangles, two leaving and two arriving). The rule:
//  - every edge's triangles are paired, one leaving each end with one
//    arriving at it (an oriented surface crosses an edge once each way); the
//    i-th triangle running from the smaller point id to the larger (in
//    triangle order) with the i-th running back, rotated when that pairing
//    would join the same two fans twice (below);
//  - around each point the corners linked through paired edges form its
//    fans; a point with more than one fan becomes one point per fan: the fan
//    holding the point's first corner keeps the id, the others get new ids
//    after the last point (by point id, then by first corner), carrying a
//    copy of the point's position and fields.
// A copy sits where the point sits: both sheets passed nearest that grid
// point, and the mean of their crossings is all the coarse mesh knows.
// check reports these as duplicate points.
// An edge whose pairs would join the same two fans at both ends (after the
// split still two edges on one pair of points) gets the next rotation of
// its pairing, in sweeps over those edges in key order until none changes
// (at most four): each rotation pairs a leaving triangle with another
// arriving one, which splits both ends along the edge.
// Guaranteed: every edge with as many triangles leaving as arriving at each
// end is manifold afterwards unless no rotation separates its pairs (counted
// in edges_left); every point has one fan. Edges crossed more often one way
// than the other (an open surface's border, or a fold's one-way repeats)
// keep their unpaired triangles as boundary. Triangles, their order and the
// points' order are kept; deterministic, the same at any thread count.
#include <cstdint>
#include <functional>
#include <vector>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::generate {

struct NonmanifoldSplit {
  Id points_added = 0;  // the copies appended
  Id edges_left = 0;    // edges whose pairs no rotation separates
  // The points no triangle refers to, ascending, found on the way and left
  // in place (keymesh::remove_points takes them out without another scan).
  std::vector<PointIndex> unused;
  // The copies, in the order appended (copy i is point n + i): the point
  // whose fan it took (an original or an earlier copy) and the round
  // (1 to 4) that made it. And the points the first round looked at
  // (ascending): every point that was not one closed fan.
  std::vector<PointIndex> split_from;
  std::vector<std::uint8_t> copy_round;
  std::vector<PointIndex> first_flagged;
  int rounds = 0;  // rounds run
};

// Triangles only (InputError otherwise, and for a corner referring to a
// point past the last); a triangle that repeats a point id keeps its
// corners there in one fan.
NonmanifoldSplit split_nonmanifold(SurfaceMesh& mesh);

// Where to look, as a caller that made the mesh may know it.
struct TriangleRange {
  Id begin = 0, end = 0;  // triangles [begin, end)
};
struct NonmanifoldSuspects {
  // Ascending ids: every point that is not one closed fan, and maybe more
  // (the rule leaves a point of one closed fan as it is).
  std::vector<PointIndex> points;
  // Ascending, disjoint: ranges holding every triangle at those points;
  // empty: all triangles.
  std::vector<TriangleRange> triangles;
};

// The same, told where to look: every point has a triangle and every corner
// refers to a point of the mesh, as the caller knows (the contour's coarse
// pass finds the suspects from its voxels, generate/coarse_fans.hpp, and
// numbers no point without a triangle; the suspects' triangles are in the
// voxel rows around them). `unused` stays empty. The same result as the
// form above on such a mesh, without grouping every corner by point; a point
// missing from the suspects (or a triangle from the ranges) is left as it
// is. Lists out of order are refused (InputError).
NonmanifoldSplit split_nonmanifold(SurfaceMesh& mesh, const NonmanifoldSuspects& suspects);

// Parts of one mesh split apart, each with a margin of its neighbours'
// (the distributed contour's ranks, docs/decisions/contour-coarsen-pieces.md):
// a decision of the rule reaches along chains of points that are not one
// closed fan, and how many rounds run depends on the whole mesh (a round
// follows one that added a copy and left an edge joined). So the rounds are
// agreed: after each, `go_on` (collective) is told the copies this part
// added of the points it `counts` and the edges left joined whose smaller
// end it counts, and says whether any part added a copy and left an edge.
struct SplitRounds {
  std::function<bool(PointIndex)> counts;
  std::function<bool(Id added, Id left)> go_on;
};

// The whole-mesh form on one part, with agreed rounds (edges_left: this
// part's count).
NonmanifoldSplit split_nonmanifold_part(SurfaceMesh& mesh, const SplitRounds& rounds);

}  // namespace keymesh::generate
