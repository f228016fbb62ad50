#pragma once
// What a reader's result must satisfy whatever bytes it was given: a reader
// either throws InputError/LimitError or returns something every later stage
// can use without further checks. A violation is a bug: std::logic_error
// (an abort under libFuzzer, a failed test in the replay).
#include <cmath>
#include <stdexcept>
#include <string>

#include "io/mesh_bytes.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::fuzz {

inline void expect_valid(const SurfaceMesh& mesh) {
  try {
    io::mesh_bytes::validate_mesh(mesh, "reader result");
  } catch (const InputError& e) {
    throw std::logic_error(std::string("reader returned an invalid mesh: ") + e.what());
  }
}

inline void expect_valid(const UnstructuredGrid& grid) {
  try {
    grid.validate("reader result");
  } catch (const InputError& e) {
    throw std::logic_error(std::string("reader returned an invalid grid: ") + e.what());
  }
}

inline void expect_valid(const ImageGrid& grid) {
  for (int a = 0; a < 3; ++a) {
    if (grid.dims[a] <= 0) throw std::logic_error("reader returned a grid with a non-positive dimension");
    if (!(grid.spacing[a] > 0) || !std::isfinite(grid.spacing[a]))
      throw std::logic_error("reader returned a grid with a bad spacing");
    if (!std::isfinite(grid.origin[a])) throw std::logic_error("reader returned a grid with a non-finite origin");
  }
  if (grid.bytes.size() != static_cast<std::size_t>(grid.num_points()) * scalar_size(grid.type))
    throw std::logic_error("reader returned a grid whose samples do not match its dims");
}

}  // namespace keymesh::fuzz
