#pragma once
// Label maps for the label tests.
#include <array>
#include <cstdint>

#include "keymesh/mesh/image_grid.hpp"

namespace keymesh::test {

// A uint8 label map of dims n, filled by f(i, j, k).
template <class F>
ImageGrid label_map(std::array<Id, 3> n, F&& f) {
  ImageGrid g;
  g.allocate(n, ScalarType::UInt8);
  auto* v = reinterpret_cast<std::uint8_t*>(g.data());
  for (Id k = 0; k < n[2]; ++k)
    for (Id j = 0; j < n[1]; ++j)
      for (Id i = 0; i < n[0]; ++i) v[i + n[0] * (j + n[1] * k)] = static_cast<std::uint8_t>(f(i, j, k));
  return g;
}

}  // namespace keymesh::test
