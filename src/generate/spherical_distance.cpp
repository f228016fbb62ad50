#include "keymesh/generate/spherical_distance.hpp"

#include <cmath>
#include <string>

#include "keymesh/parallel/for_each.hpp"

namespace keymesh::generate {

ImageGrid spherical_distance(Id n) {
  if (n < 2) throw InputError("spherical distance field: size " + std::to_string(n) + " (need at least 2)");
  ImageGrid grid;
  grid.allocate({n, n, n}, ScalarType::Float32);
  grid.name = "distance";
  float* v = static_cast<float*>(grid.data());
  const double c = static_cast<double>(n / 2);
  parallel::for_each(n * n, [&](Id row) {
    const double dy = static_cast<double>(row % n) - c;
    const double dz = static_cast<double>(row / n) - c;
    float* out = v + row * n;
    for (Id i = 0; i < n; ++i) {
      const double dx = static_cast<double>(i) - c;
      out[i] = static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz));
    }
  }, 16);
  return grid;
}

}  // namespace keymesh::generate
