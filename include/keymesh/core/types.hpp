#pragma once
// Basic index and key types shared by every layer.
#include <cstdint>

namespace keymesh {

// Signed 64-bit count/index for sizes: never overflows for any array that fits
// in memory. Mesh connectivity is stored as uint32 (see SurfaceMesh) and
// anything that would not fit is refused by name before allocation.
using Id = std::int64_t;

// Output point index inside a mesh's connectivity.
using PointIndex = std::uint32_t;

}  // namespace keymesh
