#include "collinear_triangles.hpp"

#include <array>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace keymesh::io::neuroglancer {

namespace {

using Edge = std::pair<std::uint32_t, std::uint32_t>;  // directed

struct Lines {
  const QuantizedMesh& mesh;

  std::array<std::int64_t, 3> at(std::uint32_t p) const {
    return {mesh.positions[3 * p], mesh.positions[3 * p + 1], mesh.positions[3 * p + 2]};
  }

  // The corner (0-2) strictly between the other two when the triangle's
  // corners are distinct and on one line; -1 otherwise. Integers below 2^16:
  // the cross product is exact in 64 bits.
  int middle(std::size_t t) const {
    const std::uint32_t* c = mesh.triangles.data() + 3 * t;
    const auto p = at(c[0]), q = at(c[1]), r = at(c[2]);
    std::array<std::int64_t, 3> u{}, v{};
    for (int a = 0; a < 3; ++a) u[a] = q[a] - p[a], v[a] = r[a] - p[a];
    if (u[1] * v[2] != u[2] * v[1] || u[2] * v[0] != u[0] * v[2] || u[0] * v[1] != u[1] * v[0]) return -1;
    if (p == q || q == r || p == r) return -1;
    const std::array<std::int64_t, 3> x[3] = {p, q, r};
    for (int m = 0; m < 3; ++m) {
      const auto &lo = x[(m + 1) % 3], &hi = x[(m + 2) % 3];
      for (int a = 0; a < 3; ++a)
        if (lo[a] != hi[a]) {
          if ((x[m][a] - lo[a]) * (x[m][a] - hi[a]) < 0) return m;
          break;
        }
    }
    return -1;
  }
};

}  // namespace

int flip_collinear_triangles(QuantizedMesh& mesh) {
  const Lines lines{mesh};
  const std::size_t n = mesh.triangles.size() / 3;
  std::vector<std::size_t> flat;
  for (std::size_t t = 0; t < n; ++t)
    if (lines.middle(t) >= 0) flat.push_back(t);
  if (flat.empty()) return 0;
  std::map<Edge, std::vector<std::size_t>> holders;  // directed edge -> triangles
  auto edges = [&](std::size_t t, bool add) {
    for (int k = 0; k < 3; ++k) {
      const Edge e{mesh.triangles[3 * t + k], mesh.triangles[3 * t + (k + 1) % 3]};
      auto& h = holders[e];
      if (add) {
        h.push_back(t);
      } else {
        std::erase(h, t);
      }
    }
  };
  for (std::size_t t = 0; t < n; ++t) edges(t, true);
  // Whether a triangle on the points {x, y, z} exists (either orientation).
  auto exists = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    for (const Edge& e : {Edge{x, y}, Edge{y, x}})
      for (std::size_t h : holders[e])
        for (int k = 0; k < 3; ++k)
          if (mesh.triangles[3 * h + k] == z) return true;
    return false;
  };
  int flipped = 0;
  for (bool again = true; again;) {
    again = false;
    for (std::size_t t : flat) {
      const int m = lines.middle(t);
      if (m < 0) continue;  // flipped already
      std::uint32_t* c = mesh.triangles.data() + 3 * t;
      const std::uint32_t b = c[m], cc = c[(m + 1) % 3], a = c[(m + 2) % 3];
      const auto& across = holders[{a, cc}];
      if (across.size() != 1 || holders[{cc, a}].size() != 1 || lines.middle(across[0]) >= 0) continue;
      const std::size_t u = across[0];
      std::uint32_t* o = mesh.triangles.data() + 3 * u;
      std::uint32_t d = o[0] != a && o[0] != cc ? o[0] : o[1] != a && o[1] != cc ? o[1] : o[2];
      if (exists(a, b, d) || exists(b, cc, d)) continue;  // would double a triangle: a fold, not a line
      edges(t, false), edges(u, false);
      c[0] = a, c[1] = b, c[2] = d;
      o[0] = b, o[1] = cc, o[2] = d;
      edges(t, true), edges(u, true);
      ++flipped, again = true;
    }
  }
  return flipped;
}

}  // namespace keymesh::io::neuroglancer
