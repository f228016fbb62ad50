#pragma once
// Measures of test meshes computed independently of the library.
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::test {

// Signed volume enclosed by a closed triangle mesh (divergence theorem):
// positive when the triangles face outward.
inline double enclosed_volume(const SurfaceMesh& m) {
  double v = 0;
  for (Id t = 0; t < m.num_cells(); ++t) {
    const float* a = &m.points[3 * m.connectivity[3 * t]];
    const float* b = &m.points[3 * m.connectivity[3 * t + 1]];
    const float* c = &m.points[3 * m.connectivity[3 * t + 2]];
    v += (double(a[0]) * (double(b[1]) * c[2] - double(b[2]) * c[1]) -
          double(a[1]) * (double(b[0]) * c[2] - double(b[2]) * c[0]) +
          double(a[2]) * (double(b[0]) * c[1] - double(b[1]) * c[0])) / 6.0;
  }
  return v;
}

}  // namespace keymesh::test
