#pragma once
// The paper's synthetic "Spherical Distance" field (Table 1): the Euclidean
// distance, in voxel units, of every grid point from grid point (N/2, N/2, N/2)
// of an N^3 grid, as float32 with unit spacing and zero origin.
//
// With iso = N/2 - 1 + 0.001 an edge-based marching cubes gives the paper's
// triangle counts (149,420 / 607,388 / 2,451,212 at 128^3 / 256^3 / 512^3);
// that surface touches the +x/+y/+z faces of the box. iso = N/2 - 1.5 gives a
// closed sphere (Euler characteristic 2).
#include "keymesh/mesh/image_grid.hpp"

namespace keymesh::generate {

// Throws InputError when n < 2.
ImageGrid spherical_distance(Id n);

}  // namespace keymesh::generate
