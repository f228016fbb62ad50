#pragma once
// Inputs shared by the dual's CPU-path and device-path tests (dual_test.cpp,
// dual_device_test.cpp).
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::testing {

// The sphere of radius iso in spherical_distance(n): closed, with averaged
// normals and mean curvature, the point fields the dual carries.
inline SurfaceMesh dual_sphere(Id n, double iso) {
  generate::ContourOptions o;
  o.isovalues = {iso};
  o.normals = generate::ContourNormals::Average;
  o.curvature = true;
  return generate::contour(generate::spherical_distance(n), o);
}

// A 3 x 3 grid of points as 8 triangles (open), plus a bowtie: two
// triangles meeting only at point 9 (a non-manifold point). Points 0..13.
inline SurfaceMesh open_grid_and_bowtie() {
  SurfaceMesh m;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) m.points.insert(m.points.end(), {float(i), float(j), 0.f});
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      const PointIndex a = PointIndex(i + 3 * j), b = a + 1, c = a + 3, d = a + 4;
      m.connectivity.insert(m.connectivity.end(), {a, b, d, a, d, c});
    }
  m.points.insert(m.points.end(), {5, 0, 0, 6, -1, 0, 6, 1, 0, 4, -1, 0, 4, 1, 0});  // points 9..13
  m.connectivity.insert(m.connectivity.end(), {9, 10, 11, 9, 12, 13});
  return m;
}

}  // namespace keymesh::testing
