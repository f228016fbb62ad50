#pragma once
// A GridShape of nx x ny x nz samples, x fastest, unit spacing (the
// structured contour's tests build their grids' shapes with it).
#include "keymesh/generate/contour/contour_kernels.hpp"

namespace keymesh::generate {

inline GridShape grid_shape(Id nx, Id ny, Id nz) {
  GridShape s{};
  s.nx = nx, s.ny = ny, s.nz = nz;
  s.nxy = s.nx * s.ny, s.n = s.nxy * s.nz;
  s.stride[0] = 1, s.stride[1] = s.nx, s.stride[2] = s.nxy;
  s.table = &marching_cubes_table();
  return s;
}

}  // namespace keymesh::generate
