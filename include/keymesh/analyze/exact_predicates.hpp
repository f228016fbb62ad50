#pragma once
// Exact orientation predicates over float coordinates: the sign of a
// determinant decided without rounding error, as a self-intersection check
// needs (a triangle that touches another at one point is told apart from one
// that misses it by a hair, and points on a common grid face are exactly
// coplanar). Each predicate first evaluates in double with a bound on its
// rounding error (Shewchuk's orient3d/orient2d error bounds); only when the
// result is inside that bound is it redone exactly: in 128-bit integers when
// the coordinates' exponents are close enough, otherwise with GMP.
namespace keymesh::analyze {

// Sign (-1, 0, +1) of det[b - a; c - a; d - a]: positive when d lies on the
// side of the plane (a, b, c) that the right-hand normal (b-a)x(c-a) points to.
int orient3d(const float* a, const float* b, const float* c, const float* d);

// Sign of the 2D orientation of (a, b, c) projected along axis `drop`
// (0, 1 or 2: that coordinate ignored, the other two kept in cyclic order):
// positive when a -> b -> c turns counter-clockwise.
int orient2d(const float* a, const float* b, const float* c, int drop);

}  // namespace keymesh::analyze
