#pragma once
// Points no cell refers to, removed: what a coarsening leaves where every
// triangle around a coarse point collapsed or folded away (a blob smaller
// than a voxel, the tip of a thin part). A surface handed to the user
// carries none (`keymesh check` counts them as unused points), as
// vtkCleanPolyData, PyVista's clean() or trimesh's
// remove_unreferenced_vertices would leave it.
#include <vector>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh {

// Drops the points no cell refers to, with their point fields' tuples; the
// others keep their order (new ids by a prefix sum over the used points) and
// the cells are rewritten through it. Cells and cell fields are kept.
// Returns the points removed; when none, nothing is touched but a scan of
// the cells. InputError (the mesh untouched) when a cell refers to a point
// past the last. Deterministic, the same at any thread count.
Id remove_unused_points(SurfaceMesh& mesh);

// The same for points the caller knows no cell refers to (`unused`,
// ascending ids; split_nonmanifold finds them on its way), without the
// scan: the corners are rewritten once. InputError for ids out of range or
// out of order; a listed point a cell still refers to, or a cell referring
// to a point past the last, is the caller's bug (split_nonmanifold has
// checked the latter).
void remove_points(SurfaceMesh& mesh, const std::vector<PointIndex>& unused);

}  // namespace keymesh
