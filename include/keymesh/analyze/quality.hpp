#pragma once
// Triangle quality (the paper's Section 6.1, after Bank and Smith):
//
//   Q = 4 sqrt(3) a / (h1^2 + h2^2 + h3^2)
//
// with a the area and h1..h3 the edge lengths: 1 for an equilateral triangle,
// 0 for a degenerate one.
#include <array>
#include <vector>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::analyze {

struct QualityReport {
  Id triangles = 0;
  double min = 0, median = 0, mean = 0;
  double fraction_above_0_6 = 0;         // share of triangles with Q > 0.6
  std::array<Id, 10> histogram{};        // counts of Q in [0, 0.1), [0.1, 0.2), ..., [0.9, 1]
};

// Q of every triangle (polygons are refused: InputError).
std::vector<double> triangle_quality(const SurfaceMesh& mesh);
QualityReport quality(const SurfaceMesh& mesh);

}  // namespace keymesh::analyze
