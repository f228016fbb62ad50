#pragma once
// The exact test of one pair of triangles behind find_self_intersections
// (keymesh/analyze/self_intersections.hpp): do they meet outside the convex
// hull of their common corners?
//
// Most pairs a broad phase hands over are neighbours, decided by which side
// of one triangle's plane the other's corners lie on. That side is asked in
// one of two ways with the same answers: orient3d (exact_predicates.hpp) for
// any float corners, or, when every coordinate of the mesh is an integer of
// magnitude at most 2^19 (a quantized mesh, as the multilod writer's), from
// the triangle's plane computed once in 64-bit integers (normal and offset
// below 2^62, so n . p - offset is exact): a few multiplications instead of
// a filtered determinant per corner; corners compared by one key each; and
// the rarer orientations of four corners in 64-bit integers too.
#include <array>
#include <cstddef>
#include <cstdint>

namespace keymesh::analyze::detail {

using Tri = std::array<const float*, 3>;

// An axis along which the triangle projects with non-zero area (-1: none, the
// triangle has no area). Any such axis decides 2D tests in its plane exactly.
int projection_axis(const Tri& t);

// A triangle with integer corners: its plane, side(p) = sign(normal . p -
// offset), the sign of orient3d(t[0], t[1], t[2], p); and its corners'
// positions as keys, equal where the positions are.
struct IntegerTriangle {
  std::array<std::int64_t, 3> normal{};
  std::int64_t offset = 0;
  std::array<std::uint64_t, 3> corner_key{};
};

// Whether all `count` values are integers of magnitude at most 2^19, where
// integer_triangle and the test with it are exact.
bool integer_coordinates(const float* values, std::size_t count);
IntegerTriangle integer_triangle(const Tri& t);
// orient3d for integer coordinates within the bound: differences below
// 2^21, each of the determinant's six products below 2^60, exact in int64.
int orient3d_integer(const float* a, const float* b, const float* c, const float* d);
// The exact integers of a coordinate within the bound.
inline std::int64_t integer(float v) { return static_cast<std::int64_t>(v); }

// p's side of t's plane: -1, 0, +1 (p's coordinates integers within the bound too).
inline int side(const IntegerTriangle& t, const float* p) {
  const std::int64_t v = t.normal[0] * integer(p[0]) + t.normal[1] * integer(p[1]) + t.normal[2] * integer(p[2]) - t.offset;
  return (v > 0) - (v < 0);
}

// The integer test's shortcut, from t's corners' sides of u's plane, exact,
// so a common corner is on it at no extra cost: -1 when t meets u's plane
// only in common corners (the pair does not cross), +1 when all its
// corners are common (the same triangle twice), 0 undecided. The answers
// the full test gives, from three plane sides and keys compared only for
// the corners on the plane (neighbours' common corners). Inline: most
// pairs a broad phase hands over end here.
inline int decide_by_sides(const Tri& t, const IntegerTriangle& t_integer, const IntegerTriangle& u) {
  int above = 0, below = 0;
  for (int k = 0; k < 3; ++k) {
    const int s = side(u, t[k]);
    const std::uint64_t key = t_integer.corner_key[k];
    if (s == 0 && key != u.corner_key[0] && key != u.corner_key[1] && key != u.corner_key[2]) return 0;
    above += s > 0;
    below += s < 0;
  }
  if (above == 0 && below == 0) return 1;
  return above == 0 || below == 0 ? -1 : 0;
}

// The pair test, both triangles with area along their projection axes
// drop_a, drop_b (projection_axis): with orient3d, or, integer corners
// within the bound, in 64-bit integers (cross_undecided: past the shortcut).
bool cross_projected(const Tri& a, const Tri& b, int drop_a, int drop_b);
bool cross_undecided(const Tri& a, const Tri& b, int drop_a, int drop_b, const IntegerTriangle& integer_a,
                     const IntegerTriangle& integer_b);
inline bool cross_projected(const Tri& a, const Tri& b, int drop_a, int drop_b, const IntegerTriangle& integer_a,
                            const IntegerTriangle& integer_b) {
  const int b_by_a = decide_by_sides(b, integer_b, integer_a);
  if (b_by_a != 0) return b_by_a > 0;
  if (decide_by_sides(a, integer_a, integer_b) < 0) return false;
  return cross_undecided(a, b, drop_a, drop_b, integer_a, integer_b);
}

}  // namespace keymesh::analyze::detail
