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
#include "label_map.hpp"

using namespace keymesh;

namespace {

// Labels 1..labels: per voxel the label whose noise field is largest, the
// fields box-filtered `passes` times (blobs a few voxels wide; 0 passes:
// every voxel its own). splitmix64 noise, the same on every platform.
ImageGrid argmax_noise(std::array<Id, 3> n, int labels, std::uint64_t seed, int passes) {
  const Id count = n[0] * n[1] * n[2];
  std::vector<float> field(static_cast<std::size_t>(labels * count));
  std::uint64_t s = seed;
  for (float& f : field) {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    f = static_cast<float>((z ^ (z >> 31)) >> 40) / 16777216.0f;
  }
  const Id stride[3] = {1, n[0], n[0] * n[1]};
  std::vector<float> tmp(field.size());
  for (int p = 0; p < passes; ++p)
    for (int a = 0; a < 3; ++a) {
      for (Id v = 0; v < count; ++v) {
        const Id c = (v / stride[a]) % n[a];
        const Id lo = v + ((c + n[a] - 1) % n[a] - c) * stride[a], hi = v + ((c + 1) % n[a] - c) * stride[a];
        for (int l = 0; l < labels; ++l)
          tmp[l * count + v] = (field[l * count + lo] + field[l * count + v] + field[l * count + hi]) / 3;
      }
      field.swap(tmp);
    }
  return test::label_map(n, [&](Id i, Id j, Id k) {
    const Id v = i + j * stride[1] + k * stride[2];
    int best = 0;
    for (int l = 1; l < labels; ++l)
      if (field[l * count + v] > field[best * count + v]) best = l;
    return best + 1;
  });
}

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
