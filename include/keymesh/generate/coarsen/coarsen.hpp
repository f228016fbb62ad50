#pragma once
// Coarsening by key (paper, Section 6.1, Table 5): every point of a surface
// gets a coarser key (for a contour: the input grid point nearest to it on
// its edge), KEY-REDUCE merges the points that share one, averaging their
// positions and fields ("Normals" renormalised), the index map rewrites the
// triangles, and triangles left with fewer than three distinct points are
// dropped. Folds are removed too (remove_folds): two triangles on the same
// three points facing opposite ways cancel. Then non-manifold points are
// split (split_nonmanifold.hpp) and points left without a triangle removed
// (mesh/unused_points.hpp). Cell fields (a label surface's boundary_labels)
// follow their triangles: a kept triangle keeps its tuple. Deterministic:
// each group averages its points in increasing index.
#include <cstdint>
#include <vector>

#include "keymesh/generate/coarsen/split_nonmanifold.hpp"
#include "keymesh/mesh/normals.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::generate {

struct CoarsenStats {
  Id points_before = 0, points_after = 0;
  Id triangles_before = 0, triangles_after = 0;
  Id folded = 0;  // triangles removed by remove_folds
};

// Removes triangles over the same three points: pairs facing opposite ways
// cancel, repeats facing one way are kept once (the kept one's cell field
// tuples with it). Returns the number removed.
Id remove_folds(SurfaceMesh& mesh);
// The same over the triangles from `first_triangle` on of a triangle list
// without cell fields, for the sets of equal triangles whose points are all
// below `complete_below` (the others may still gain members: they are left
// as they are, to be decided again). Returns the first triangle from
// first_triangle on that was left undecided (the end when none). For the
// streamed coarsening's slabs (coarsen/coarsen_slabs.hpp).
Id remove_complete_folds(Array<PointIndex>& connectivity, Id first_triangle, PointIndex complete_below);
// (The structured contour applies the same rule in its own triangle pass,
// src/generate/coarsen/coarse_folds.hpp, without comparing triangles.)

// coarsen()'s input checks, whichever device runs it (InputError): triangles
// only, one key per point, every key < key_range.
void check_coarsen_input(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys, std::uint64_t key_range);

// `keys[p]` is point p's coarse key, every key < key_range (dense plan).
SurfaceMesh coarsen(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys, std::uint64_t key_range,
                    CoarsenStats* stats = nullptr);

// One part of a mesh that other processes coarsen beside it (a rank's slab
// and halo): the same, with the split's rounds agreed (split_nonmanifold.hpp,
// SplitRounds) and what the split did returned in `split`; the points left
// without a triangle (split.unused) are not removed.
SurfaceMesh coarsen_part(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys, std::uint64_t key_range,
                         const SplitRounds& rounds, NonmanifoldSplit& split);

// Point normals live in the mesh layer (mesh/normals.hpp): coarsening
// renormalises averaged ones and callers re-average after it with
// keymesh::average_normals.

}  // namespace keymesh::generate
