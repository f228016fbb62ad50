#pragma once
// Inputs and messages shared by the voxel contour's device-path tests
// (contour_device_test.cpp, contour_device_plans_test.cpp,
// contour_device_resident_test.cpp).
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "uniform_noise.hpp"

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
  ImageGrid g = uniform_noise({nx, ny, nz}, seed);
  g.origin = {-1.5, 0.25, 3.0};
  g.spacing = {0.5, 1.25, 0.75};
  return g;
}

// Whole-number samples in [lo, hi] of type T (many exactly on an integer
// isovalue), on an n x (n + 3) x (n - 2) grid.
template <class T>
ImageGrid integer_noise(Id n, int lo, int hi, unsigned seed, ScalarType type) {
  ImageGrid g;
  g.allocate({n, n + 3, n - 2}, type);
  T* v = static_cast<T*>(g.data());
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> u(lo, hi);
  for (Id i = 0; i < g.num_points(); ++i) v[i] = static_cast<T>(u(rng));
  return g;
}

// Every fifth sample of a float32 grid set to NaN, +inf, -inf in turn.
inline ImageGrid with_nan_and_infinity(ImageGrid g) {
  float* v = static_cast<float*>(g.data());
  const float specials[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                            -std::numeric_limits<float>::infinity()};
  for (Id i = 0; i < g.num_points(); i += 5) v[i] = specials[(i / 5) % 3];
  return g;
}

// One-voxel-thick float32 grids (2 x 17 x 19, 23 x 2 x 2, 9 x 11 x 2) of
// sin(0.7 i): a surface at 0.1 cuts each.
inline std::vector<ImageGrid> thin_grids() {
  std::vector<ImageGrid> grids;
  for (auto dims : {std::array<Id, 3>{2, 17, 19}, std::array<Id, 3>{23, 2, 2}, std::array<Id, 3>{9, 11, 2}}) {
    ImageGrid g;
    g.allocate({dims[0], dims[1], dims[2]}, ScalarType::Float32);
    float* v = static_cast<float*>(g.data());
    for (Id i = 0; i < g.num_points(); ++i) v[i] = static_cast<float>(std::sin(0.7 * double(i)));
    grids.push_back(std::move(g));
  }
  return grids;
}

// A 12^3 uint8 volume, 200 on the plane k = 5 and 0 elsewhere.
inline ImageGrid one_voxel_plate() {
  ImageGrid plate;
  plate.allocate({12, 12, 12}, ScalarType::UInt8);
  auto* p = static_cast<std::uint8_t*>(plate.data());
  for (Id i = 0; i < plate.num_points(); ++i) p[i] = (i / 144 == 5) ? 200 : 0;
  return plate;
}

}  // namespace keymesh::testing
