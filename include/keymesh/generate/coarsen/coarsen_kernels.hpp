#pragma once
// The per-element arithmetic of coarsening (coarsen.hpp), shared by its CPU
// path (src/generate/coarsen/coarsen.cpp) and its device path
// (coarsen_device.hpp): plain functions, KEYMESH_HD, so that every device
// computes the same bits.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "keymesh/core/device.hpp"
#include "keymesh/core/types.hpp"

namespace keymesh::generate::coarsening {

// Component c of the mean of a group's tuples (k components each): the
// tuples of pairs order[b], ..., order[e - 1] summed in double from +0 in
// that order, divided by their count, rounded to float once.
KEYMESH_HD inline float group_mean(const float* in, int k, int c, const std::uint32_t* order, Id b, Id e) {
  double s = 0;
  for (Id j = b; j < e; ++j) s += in[order[j] * static_cast<std::size_t>(k) + static_cast<std::size_t>(c)];
  return static_cast<float>(s / static_cast<double>(e - b));
}

// An averaged normal made unit again, in float (left as it is when zero).
KEYMESH_HD inline void renormalize(float* v) {
  const float l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (l > 0) v[0] /= l, v[1] /= l, v[2] /= l;
}

// Whether a triangle's three corners are three points.
KEYMESH_HD inline bool distinct(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  return a != b && b != c && a != c;
}

// A triangle as its point set: the smallest id first, the other two in
// increasing order, and its orientation (+1 when rotating the smallest id to
// the front leaves the other two increasing).
struct TriangleSet {
  std::uint32_t lo, mid, hi;
  std::int8_t sign;
};

KEYMESH_HD inline TriangleSet triangle_set(const PointIndex* C, Id t) {
  const std::uint32_t v[3] = {C[3 * t], C[3 * t + 1], C[3 * t + 2]};
  // Rotating the smallest id to the front keeps the orientation; the order
  // of the other two then tells it.
  const int r = v[0] < v[1] ? (v[0] < v[2] ? 0 : 2) : (v[1] < v[2] ? 1 : 2);
  const std::uint32_t a = v[r], b = v[(r + 1) % 3], c = v[(r + 2) % 3];
  return TriangleSet{a, b < c ? b : c, b < c ? c : b, static_cast<std::int8_t>(b < c ? 1 : -1)};
}

}  // namespace keymesh::generate::coarsening
