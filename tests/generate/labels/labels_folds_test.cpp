// The smoothed label surfaces cross nowhere and hold no zero-area triangle
// (docs/decisions/labels-smoothing-folds.md): many-label noise volumes,
// where three or more labels meet all over, the network and every label's
// own surface, both methods, checked with the exact predicates.
#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <sstream>
#include <vector>

#include "keymesh/analyze/self_intersections.hpp"
#include "keymesh/generate/labels/labels.hpp"
#include "argmax_noise.hpp"

using namespace keymesh;
using test::argmax_noise;

namespace {

// The triangles of `mesh` whose cell field `label` is `value` (all when
// value < 0), as a mesh of their own.
SurfaceMesh part(const SurfaceMesh& mesh, float value) {
  if (value < 0) return mesh;
  const Field* label = mesh.find_cell_field("label");
  SurfaceMesh out;
  out.points = mesh.points;
  for (Id t = 0; t < mesh.num_cells(); ++t)
    if (label->values[t] == value)
      for (int k = 0; k < 3; ++k) out.connectivity.push_back(mesh.connectivity[3 * t + k]);
  return out;
}

// "crossing pairs / zero-area triangles" of each surface that has any.
std::string folds(const SurfaceMesh& mesh, bool per_label) {
  std::map<float, int> values{{-1.0f, 0}};
  if (per_label) {
    values.clear();
    const Field* label = mesh.find_cell_field("label");
    for (Id t = 0; t < mesh.num_cells(); ++t) values[label->values[t]] = 0;
  }
  std::ostringstream out;
  for (const auto& [value, unused] : values) {
    const auto r = analyze::find_self_intersections(part(mesh, value));
    if (r.self_intersections || r.zero_area_triangles)
      out << " label " << value << ": " << r.self_intersections << " / " << r.zero_area_triangles;
  }
  return out.str();
}

struct Case {
  int labels, passes;
  std::uint64_t seed;
};

constexpr Case kCases[] = {{5, 1, 1}, {12, 2, 2}, {24, 1, 3}, {40, 2, 4}, {31, 2, 17}, {5, 0, 7}};

}  // namespace

// The surface nets network (one surface) and every label's own surface.
TEST(LabelsFolds, SurfaceNetsCrossNowhere) {
  for (const Case& c : kCases) {
    const ImageGrid g = argmax_noise({24, 22, 20}, c.labels, c.seed, c.passes);
    for (bool per_label : {false, true}) {
      generate::LabelOptions o;
      o.per_label = per_label;
      EXPECT_EQ(folds(generate::contour_labels(g, o), per_label), "")
          << c.labels << " labels, seed " << c.seed << (per_label ? ", per label" : ", network");
    }
  }
}

// Discrete marching cubes: the network repeats a face shared by two labels
// in both labels' surfaces, so each label's surface is checked on its own.
TEST(LabelsFolds, DiscreteMarchingCubesCrossNowhere) {
  for (const Case& c : kCases) {
    const ImageGrid g = argmax_noise({24, 22, 20}, c.labels, c.seed, c.passes);
    for (bool per_label : {false, true}) {
      generate::LabelOptions o;
      o.method = generate::LabelMethod::DiscreteMarchingCubes;
      o.per_label = per_label;
      EXPECT_EQ(folds(generate::contour_labels(g, o), true), "")
          << c.labels << " labels, seed " << c.seed << (per_label ? ", per label" : ", network");
    }
  }
}
