#include "triangle_crossing.hpp"

#include <cmath>

#include "keymesh/analyze/exact_predicates.hpp"

namespace keymesh::analyze::detail {

namespace {

constexpr float kIntegerBound = 524288.0f;  // 2^19: the products below stay under 2^63

bool same_position(const float* p, const float* q) { return p[0] == q[0] && p[1] == q[1] && p[2] == q[2]; }

// p in the closed triangle t (p in t's plane; t projects with area along drop).
bool in_closed_triangle(const float* p, const Tri& t, int drop) {
  const int s = orient2d(t[0], t[1], t[2], drop);
  for (int k = 0; k < 3; ++k)
    if (orient2d(t[k], t[(k + 1) % 3], p, drop) == -s) return false;
  return true;
}

// Segments (p, q) and (r, s), in one plane, cross at a point inside both.
bool cross_properly(const float* p, const float* q, const float* r, const float* s, int drop) {
  if (orient2d(p, q, r, drop) * orient2d(p, q, s, drop) >= 0) return false;
  return orient2d(r, s, p, drop) * orient2d(r, s, q, drop) < 0;
}

// Edge (p, q) of one triangle against the closed triangle u: do they meet
// outside the corners the two triangles share? side_p, side_q: p's and q's
// sides of u's plane; *_shared: whether p, q are corners of u too; orient:
// orient3d or its equal.
template <class Orient3d>
bool edge_meets(const float* p, const float* q, int side_p, int side_q, bool p_shared, bool q_shared, const Tri& u,
                int drop, Orient3d orient) {
  if (p_shared && q_shared) return false;  // a common edge
  if (side_p * side_q > 0) return false;
  if (side_p == 0 && side_q == 0) {  // the edge lies in u's plane
    if (!p_shared && in_closed_triangle(p, u, drop)) return true;
    if (!q_shared && in_closed_triangle(q, u, drop)) return true;
    for (int k = 0; k < 3; ++k)
      if (cross_properly(p, q, u[k], u[(k + 1) % 3], drop)) return true;
    return false;  // a touch at one of u's corners shows from u's side
  }
  if (side_p == 0) return !p_shared && in_closed_triangle(p, u, drop);
  if (side_q == 0) return !q_shared && in_closed_triangle(q, u, drop);
  // The edge pierces u's plane at a point inside it: in u when it passes no
  // edge of u on the outside (it passes one once it passes u's edges on
  // both sides, with no need to ask the third).
  bool positive = false, negative = false;
  for (int k = 0; k < 3; ++k) {
    const int o = orient(p, q, u[k], u[(k + 1) % 3]);
    positive |= o > 0;
    negative |= o < 0;
    if (positive && negative) return false;
  }
  return true;
}

// Coplanar triangles (a projects with area along drop): do they overlap
// outside their common corners?
bool overlap_in_plane(const Tri& a, const Tri& b, const std::array<bool, 3>& a_shared,
                      const std::array<bool, 3>& b_shared, int drop) {
  for (int i = 0; i < 3; ++i)
    if (!a_shared[i] && in_closed_triangle(a[i], b, drop)) return true;
  for (int j = 0; j < 3; ++j)
    if (!b_shared[j] && in_closed_triangle(b[j], a, drop)) return true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (cross_properly(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3], drop)) return true;
  return false;
}

// The corners of `t` on the sides of a plane (side_of(p): -1, 0, +1); a
// corner in common is on it without asking. False when the free corners all
// lie strictly on one side: t meets the plane only in the common corners
// (or their edge), so the pair does not cross. With one or two common
// corners (the neighbours a mesh's broad phase gives) this ends most tests.
template <class SideOf>
bool straddles(const Tri& t, const std::array<bool, 3>& shared, SideOf side_of, std::array<int, 3>& side) {
  int free = 0, above = 0, below = 0;
  for (int k = 0; k < 3; ++k) {
    // Exactly 0 is what the double filter cannot prove: asked, a common
    // corner would cost an exact sign.
    side[k] = shared[k] ? 0 : side_of(t[k]);
    free += !shared[k];
    above += side[k] > 0;
    below += side[k] < 0;
  }
  return above != free && below != free;
}

// The pair test over its four questions: same(i, j): whether a[i] and b[j]
// are at one position; side_of_a(p): p's side of a's plane (the sign of
// orient3d(a[0], a[1], a[2], p)), side_of_b alike; orient: orient3d or its
// equal.
template <class Same, class SideOfA, class SideOfB, class Orient3d>
bool cross_with(const Tri& a, const Tri& b, int drop_a, int drop_b, Same same, SideOfA side_of_a, SideOfB side_of_b,
                Orient3d orient) {
  std::array<bool, 3> a_shared{}, b_shared{};
  int shared = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (same(i, j)) {
        a_shared[i] = b_shared[j] = true;
        ++shared;
      }
  if (shared >= 3) return true;  // the same triangle twice
  std::array<int, 3> side_b{}, side_a{};
  if (!straddles(b, b_shared, side_of_a, side_b) || !straddles(a, a_shared, side_of_b, side_a)) return false;
  if (side_b[0] == 0 && side_b[1] == 0 && side_b[2] == 0) return overlap_in_plane(a, b, a_shared, b_shared, drop_a);
  // Two planes: the triangles meet on their common line, where some edge of
  // one reaches into the other.
  for (int i = 0; i < 3; ++i) {
    const int k = (i + 1) % 3;
    if (edge_meets(a[i], a[k], side_a[i], side_a[k], a_shared[i], a_shared[k], b, drop_b, orient)) return true;
    if (edge_meets(b[i], b[k], side_b[i], side_b[k], b_shared[i], b_shared[k], a, drop_a, orient)) return true;
  }
  return false;
}

}  // namespace

int orient3d_integer(const float* a, const float* b, const float* c, const float* d) {
  std::array<std::int64_t, 9> m{};
  for (int k = 0; k < 3; ++k) {
    m[k] = integer(b[k]) - integer(a[k]);
    m[3 + k] = integer(c[k]) - integer(a[k]);
    m[6 + k] = integer(d[k]) - integer(a[k]);
  }
  const std::int64_t det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                           m[2] * (m[3] * m[7] - m[4] * m[6]);
  return (det > 0) - (det < 0);
}

namespace {

// A point's position as one key: three coordinates within the bound, each
// shifted to [0, 2^20] in 21 bits.
std::uint64_t position_key(const float* p) {
  std::uint64_t key = 0;
  for (int k = 0; k < 3; ++k) key |= static_cast<std::uint64_t>(integer(p[k]) + (std::int64_t{1} << 19)) << (21 * k);
  return key;
}

}  // namespace

int projection_axis(const Tri& t) {
  for (int drop = 0; drop < 3; ++drop)
    if (orient2d(t[0], t[1], t[2], drop) != 0) return drop;
  return -1;
}

bool integer_coordinates(const float* values, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i)
    if (!(std::fabs(values[i]) <= kIntegerBound) || values[i] != std::trunc(values[i])) return false;
  return true;
}

IntegerTriangle integer_triangle(const Tri& t) {
  std::array<std::int64_t, 3> u{}, v{};
  for (int k = 0; k < 3; ++k) {
    u[k] = integer(t[1][k]) - integer(t[0][k]);
    v[k] = integer(t[2][k]) - integer(t[0][k]);
  }
  IntegerTriangle out;
  out.normal = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  out.offset = out.normal[0] * integer(t[0][0]) + out.normal[1] * integer(t[0][1]) + out.normal[2] * integer(t[0][2]);
  for (int k = 0; k < 3; ++k) out.corner_key[k] = position_key(t[k]);
  return out;
}

bool cross_projected(const Tri& a, const Tri& b, int drop_a, int drop_b) {
  return cross_with(
      a, b, drop_a, drop_b, [&](int i, int j) { return a[i] == b[j] || same_position(a[i], b[j]); },
      [&](const float* p) { return orient3d(a[0], a[1], a[2], p); },
      [&](const float* p) { return orient3d(b[0], b[1], b[2], p); },
      [](const float* p, const float* q, const float* r, const float* s) { return orient3d(p, q, r, s); });
}

bool cross_undecided(const Tri& a, const Tri& b, int drop_a, int drop_b, const IntegerTriangle& integer_a,
                     const IntegerTriangle& integer_b) {
  return cross_with(
      a, b, drop_a, drop_b, [&](int i, int j) { return integer_a.corner_key[i] == integer_b.corner_key[j]; },
      [&](const float* p) { return side(integer_a, p); }, [&](const float* p) { return side(integer_b, p); },
      [](const float* p, const float* q, const float* r, const float* s) { return orient3d_integer(p, q, r, s); });
}

}  // namespace keymesh::analyze::detail
