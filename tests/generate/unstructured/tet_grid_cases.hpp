#pragma once
// Inputs shared by marching tetrahedra's device-path and GPU tests
// (contour_tets_device_test.cpp, tests/cuda/unstructured_cuda_test.cpp).
#include <utility>

#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"
#include "uniform_noise.hpp"

namespace keymesh::testing {

// A grid's 5-tet split with a second, two-component point field (x + 2y,
// -z), interpolated beside the scalar.
inline UnstructuredGrid tets_of(const ImageGrid& grid) {
  UnstructuredGrid g = generate::tetrahedralize5(grid);
  Field f{"xy", 2, Array<float>(static_cast<std::size_t>(2 * g.num_points()))};
  for (Id p = 0; p < g.num_points(); ++p) {
    f.values[2 * p] = g.points[3 * p] + 2 * g.points[3 * p + 1];
    f.values[2 * p + 1] = -g.points[3 * p + 2];
  }
  g.point_fields.push_back(std::move(f));
  return g;
}

// Uniform float noise in [-1, 1) on an n x (n - 1) x (n + 2) grid.
inline ImageGrid tet_noise(Id n, unsigned seed) { return uniform_noise({n, n - 1, n + 2}, seed); }

}  // namespace keymesh::testing
