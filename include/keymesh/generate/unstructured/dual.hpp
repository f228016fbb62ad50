#pragma once
// The dual of a polygon surface (paper, Section 6.2, Table 6): one polygon per
// input point, keyed by that point, through the centroids of its incident
// cells (one dual point per input cell, in cell order), ordered around the
// point by walking its fan of cells edge to edge, so the polygon turns the
// same way as the cells (its normal agrees with theirs).
//
// Where the fan is not a closed disk:
//  - boundary point (the fan is open): the polygon is the fan's centroids
//    followed by the point itself (a dual point keyed by the input point,
//    appended after the centroids); with a single cell it is skipped;
//  - non-manifold point (several fans, or a fan that meets itself): one
//    polygon per fan, each by the rule above;
//  - a closed fan of fewer than three cells: skipped.
// Skipped fans are counted; no polygon has fewer than three points.
// Point fields are carried: a centroid gets the mean over its cell's corners.
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::generate {

struct DualStats {
  Id polygons = 0;
  Id boundary_fans = 0;         // open fans (boundary points)
  Id nonmanifold_points = 0;    // points with more than one fan
  Id skipped_fans = 0;          // fans that would give fewer than 3 points
};

SurfaceMesh dual(const SurfaceMesh& mesh, DualStats* stats = nullptr);

// dual()'s refusal of bad input (point ids out of range: InputError), what
// another backend checks before it starts.
void check_dual_input(const SurfaceMesh& mesh);

}  // namespace keymesh::generate
