#pragma once
// VERTEX-WELD (Bell, Thrust's weld_vertices example; the paper's baseline,
// Section 7.1): sort the soup's points lexicographically by their float
// coordinates, keep one of each run of equal points, and map every soup point
// to its run. Coincidence is exact float equality (-0 equals +0), so points
// that should meet but differ by rounding stay apart: the fragility that
// history keys avoid.
#include <cstdint>
#include <vector>

#include "keymesh/core/array.hpp"
#include "keymesh/core/types.hpp"

namespace keymesh::weld {

struct WeldResult {
  Array<float> points;                      // x,y,z of every distinct point, in lexicographic order
  Array<std::uint32_t> index_map;           // for every soup point, its welded point
  std::vector<std::uint32_t> first;         // for every welded point, its first soup point
};

// soup_xyz holds n points (3n floats). Deterministic; throws LimitError past
// 2^32 - 1 soup points.
WeldResult vertex_weld(const float* soup_xyz, Id n);

}  // namespace keymesh::weld
