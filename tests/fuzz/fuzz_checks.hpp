#pragma once
// What a reader's result must satisfy whatever bytes it was given: a reader
// either throws InputError/LimitError or returns something every later stage
// can use without further checks. A violation is a bug: std::logic_error
// (an abort under libFuzzer, a failed test in the replay).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/mesh_bytes.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/plane_source.hpp"
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

// dims, spacing and origin (a volume's, or a plane source's header).
inline void expect_valid_geometry(const ImageGrid& grid) {
  for (int a = 0; a < 3; ++a) {
    if (grid.dims[a] <= 0) throw std::logic_error("reader returned a grid with a non-positive dimension");
    if (!(grid.spacing[a] > 0) || !std::isfinite(grid.spacing[a]))
      throw std::logic_error("reader returned a grid with a bad spacing");
    if (!std::isfinite(grid.origin[a])) throw std::logic_error("reader returned a grid with a non-finite origin");
  }
}

inline void expect_valid(const ImageGrid& grid) {
  expect_valid_geometry(grid);
  if (grid.bytes.size() != static_cast<std::size_t>(grid.num_points()) * scalar_size(grid.type))
    throw std::logic_error("reader returned a grid whose samples do not match its dims");
}

// The planes a fuzz target reads of a plane source: at most this many bytes
// (a header may declare a volume of gigabytes of fill value: a caller reads
// such a volume slab by slab, and so does the target, up to this budget).
inline constexpr std::size_t kMaxPlaneBytesRead = std::size_t{1} << 20;

// A plane source's header passes expect_valid_geometry, and read_planes
// writes every byte of the planes asked for (read twice into buffers filled
// with different bytes: equal results), a plane read alone being the same
// bytes as in a slab (what streamed and whole reads rely on).
inline void expect_valid_planes(PlaneSource& source) {
  const ImageGrid& head = source.header();
  expect_valid_geometry(head);
  const std::size_t plane =
      static_cast<std::size_t>(head.dims[0]) * static_cast<std::size_t>(head.dims[1]) * scalar_size(head.type);
  if (plane > kMaxPlaneBytesRead) return;
  const Id planes = std::min<Id>(head.dims[2], static_cast<Id>(kMaxPlaneBytesRead / plane));
  std::vector<std::byte> zeros(static_cast<std::size_t>(planes) * plane, std::byte{0});
  std::vector<std::byte> ones(zeros.size(), std::byte{0xff});
  source.read_planes(0, planes, zeros.data());
  source.read_planes(0, planes, ones.data());
  if (zeros != ones) throw std::logic_error("read_planes left bytes unwritten, or read the same planes differently");
  std::vector<std::byte> last(plane, std::byte{0x5a});
  source.read_planes(planes - 1, 1, last.data());
  if (!std::equal(last.begin(), last.end(), zeros.end() - static_cast<std::ptrdiff_t>(plane)))
    throw std::logic_error("a plane read alone differs from the same plane read with the planes before it");
}

}  // namespace keymesh::fuzz
