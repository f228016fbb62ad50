#pragma once
// Inputs and messages shared by the voxel contour's device-path tests
// (contour_device_test.cpp, contour_device_resident_test.cpp).
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/mesh/image_grid.hpp"

namespace keymesh::testing {

// An option set named for a failure message.
inline std::string describe(const generate::ContourOptions& opt, const std::string& what) {
  std::ostringstream s;
  s << what << " normals " << int(opt.normals) << " curvature " << opt.curvature << " scalars " << opt.scalars;
  return s.str();
}

// The field options a device test runs through: none, each normal kind,
// with and without curvature, no scalar (each with `coarsen` as given).
inline std::vector<generate::ContourOptions> option_sets(const std::vector<double>& isovalues, bool coarsen = false) {
  std::vector<generate::ContourOptions> sets;
  for (auto normals : {generate::ContourNormals::None, generate::ContourNormals::Gradient,
                       generate::ContourNormals::Average})
    for (bool curvature : {false, true}) {
      generate::ContourOptions opt;
      opt.isovalues = isovalues;
      opt.normals = normals;
      opt.curvature = curvature;
      opt.coarsen = coarsen;
      sets.push_back(opt);
    }
  generate::ContourOptions bare;
  bare.isovalues = isovalues;
  bare.scalars = false;
  bare.coarsen = coarsen;
  sets.push_back(bare);
  return sets;
}

// Uniform float noise in [-1, 1) (many small components, every cube case),
// with non-unit spacing and origin.
inline ImageGrid noise(Id nx, Id ny, Id nz, unsigned seed) {
  ImageGrid g;
  g.allocate({nx, ny, nz}, ScalarType::Float32);
  g.origin = {-1.5, 0.25, 3.0};
  g.spacing = {0.5, 1.25, 0.75};
  float* v = static_cast<float*>(g.data());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (Id i = 0; i < g.num_points(); ++i) v[i] = u(rng);
  return g;
}

}  // namespace keymesh::testing
