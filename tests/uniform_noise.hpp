#pragma once
// Float32 volumes of independent uniform samples, for the tests that need
// many small components and every cube case (ambiguous faces included):
// one generator, so the tests that share a seed share the samples.
#include <array>
#include <random>

#include "keymesh/mesh/image_grid.hpp"

namespace keymesh::testing {

// g's float32 samples, in point order, drawn uniform in [lo, hi) from rng
// (a caller that fills several grids from one rng keeps its sequence).
inline void fill_uniform(ImageGrid& g, std::mt19937& rng, float lo = -1.f, float hi = 1.f) {
  float* v = static_cast<float*>(g.data());
  std::uniform_real_distribution<float> u(lo, hi);
  for (Id i = 0; i < g.num_points(); ++i) v[i] = u(rng);
}

// A float32 grid of dims (unit spacing, origin 0) filled by fill_uniform
// from std::mt19937(seed).
inline ImageGrid uniform_noise(const std::array<Id, 3>& dims, unsigned seed, float lo = -1.f, float hi = 1.f) {
  ImageGrid g;
  g.allocate(dims, ScalarType::Float32);
  std::mt19937 rng(seed);
  fill_uniform(g, rng, lo, hi);
  return g;
}

}  // namespace keymesh::testing
