#pragma once
// Keys of input topology elements of unstructured meshes (paper, Section 3:
// a generated element is keyed by the input element that produced it).
//
//   edge (a, b):            (min(a, b) << bits) | max(a, b)        2 * bits bits
//   quad face (c0..c3):     the edge key of its smallest corner and the corner
//                           diagonally opposite it (in a conforming mesh no
//                           two faces share a diagonal)              2 * bits bits
//   with a level (isovalue): (level << 2 * bits) | key
//
// `bits` is the width of a point id: bits_needed(points - 1), at least 1, so
// keys of meshes under 2^32 points fit 64 bits with room for a level.
// Voxel grids need no encoder: their edge ids are implicit
// (3 * point + axis, generate/contour_kernels.hpp).
#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>

#include "keymesh/core/device.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/core/types.hpp"
#include "keymesh/parallel/radix_sort.hpp"

namespace keymesh {

struct EdgeKeys {
  int bits = 1;  // bits of a point id

  // For a mesh of `points` points; LimitError (naming `who`) when two ids do
  // not fit 64 bits.
  static EdgeKeys for_points(Id points, const std::string& who) {
    const int b = std::max(1, parallel::bits_needed<std::uint64_t>(static_cast<std::uint64_t>(std::max<Id>(points, 2) - 1)));
    if (2 * b > 64) throw LimitError(who + ": edge keys of " + std::to_string(points) + " points need over 64 bits");
    return EdgeKeys{b};
  }

  // The significant bits of a key (the sort plan's key width).
  int key_bits() const { return 2 * bits; }

  // KEYMESH_HD: the device paths key edges with the same code.
  KEYMESH_HD std::uint64_t operator()(std::uint64_t a, std::uint64_t b) const {
    return a < b ? (a << bits) | b : (b << bits) | a;
  }
  // The edge's two points, smaller first.
  KEYMESH_HD std::pair<std::uint64_t, std::uint64_t> decode(std::uint64_t key) const {
    const std::uint64_t mask = (std::uint64_t{1} << bits) - 1;
    return {(key >> bits) & mask, key & mask};
  }

  // An edge key with a level above it (e.g. the isovalue's index).
  KEYMESH_HD std::uint64_t with_level(std::uint64_t key, std::uint64_t level) const { return (level << (2 * bits)) | key; }
  KEYMESH_HD std::uint64_t level(std::uint64_t key) const { return key >> (2 * bits); }

  // A quad face given as a corner cycle: its smallest corner and the corner
  // opposite it.
  std::uint64_t quad(const std::uint64_t cycle[4]) const {
    int m = 0;
    for (int k = 1; k < 4; ++k)
      if (cycle[k] < cycle[m]) m = k;
    return (cycle[m] << bits) | cycle[(m + 2) % 4];
  }
};

}  // namespace keymesh
