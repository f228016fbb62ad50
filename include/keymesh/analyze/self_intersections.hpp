#pragma once
// Self-intersections of a surface: pairs of cells that cross or touch where
// they share nothing. Decided exactly (analyze/exact_predicates.hpp), so a
// mesh either has a crossing pair or it has not; no tolerance is involved.
//
// Two triangles are a pair when they meet anywhere outside the convex hull of
// the corners they have in common, corners being in common when their
// positions are equal (so a welded mesh and a soup with the same triangles
// give the same answer, and points a generator puts at one position on
// purpose - a sample exactly on the isovalue - are one corner). Neighbours
// sharing an edge are a pair only when they fold onto each other (coplanar
// and overlapping); identical triangles are a pair. Triangles of zero area
// (collinear or coincident corners) are counted, not tested: they hold no
// surface to cross. Polygon cells are fanned from their first point; a
// polygon's own fan triangles are not tested against each other.
//
// Broad phase: each pair of triangles whose boxes overlap is tested once.
// Up to 8192 triangles (such as a multilod chunk piece, checked once per
// fold-guard round) by a serial sort and sweep along one axis; above that by
// a uniform grid of cells about twice the mean triangle's extent, each pair
// tested in the grid cell holding the low corner of the boxes' overlap,
// threaded. The result (pairs sorted) depends on neither the broad phase nor
// the thread count.
#include <array>
#include <cstddef>
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::analyze {

struct SelfIntersectionReport {
  Id triangles = 0;            // triangles tested (polygons fanned)
  Id zero_area_triangles = 0;  // left out of the test (collinear or coincident corners)
  Id self_intersections = 0;   // distinct pairs of cells that cross
  std::vector<std::array<Id, 2>> pairs;  // the first max_listed pairs (cell ids, smaller first), sorted
};

// Which broad phase finds the candidate pairs: automatic (by size, above), or
// one of them forced (for tests: both give the same report).
enum class BroadPhase { automatic, sweep, grid };

// Throws InputError when a cell refers to a point id out of range.
SelfIntersectionReport find_self_intersections(const SurfaceMesh& mesh, std::size_t max_listed = 16,
                                               BroadPhase broad = BroadPhase::automatic);

// The exact pair test: do triangles a and b (three xyz points each) meet
// outside the convex hull of their common corners? Both must have non-zero
// area (triangle_has_area).
bool triangles_cross(const std::array<const float*, 3>& a, const std::array<const float*, 3>& b);

// Whether the triangle's corners span an area (are not collinear), exactly.
bool triangle_has_area(const std::array<const float*, 3>& t);

}  // namespace keymesh::analyze
