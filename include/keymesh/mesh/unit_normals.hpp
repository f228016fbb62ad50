#pragma once
// Unit point normals for the formats that require them (glTF's NORMAL; the
// Khronos validator's ACCESSOR_VECTOR3_NON_UNIT): what a normal becomes
// when mesh/normals.hpp's transform left it zero, or a file gave it NaN.
#include "keymesh/core/types.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh {

// Makes every normal of `normals` (3 floats per point of `mesh`) a unit
// vector, for formats that require one (glTF's NORMAL): a normal within
// 1e-4 of unit length stays as it is (bytes kept), another finite non-zero
// one is normalised, and a zero or non-finite one takes the unit sum of the
// defined normals of the points it shares a cell with, ring by ring inward
// from the rim of an undefined patch; what is left (a component or point
// with no defined normal at all, or neighbours that cancel) gets (0, 0, 1).
// Zero normals are what a contour gives where every triangle of a point
// has zero area ("average": samples equal to the isovalue) or the gradient
// vanishes ("gradient"); NaN ones come from NaN data. Polygons are cells as
// they are (no triangles needed). Deterministic: each round reads only the
// normals defined before it. Returns how many normals were changed.
Id make_unit_normals(const SurfaceMesh& mesh, float* normals);

}  // namespace keymesh
