#include "face_points.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <tuple>
#include <utility>
#include <vector>

namespace keymesh::io::neuroglancer {

namespace {

// The directed edges the triangles leave unpaired, as (from, to), with
// multiplicity: each undirected edge's net count of one direction. Only the
// edges `wanted` keeps are counted (a property of the two ends, so every
// copy of an edge is kept alike).
template <class Wanted>
std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary_edges(const QuantizedMesh& mesh, Wanted&& wanted) {
  struct Edge {
    std::uint32_t lo, hi;
    int sign;  // +1: lo -> hi
  };
  std::vector<Edge> edges;
  for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.triangles[t + k], b = mesh.triangles[t + (k + 1) % 3];
      if (wanted(a, b)) edges.push_back(a < b ? Edge{a, b, 1} : Edge{b, a, -1});
    }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) { return std::tie(x.lo, x.hi) < std::tie(y.lo, y.hi); });
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  for (std::size_t b = 0, e = 0; b < edges.size(); b = e) {
    int net = 0;
    for (e = b; e < edges.size() && edges[e].lo == edges[b].lo && edges[e].hi == edges[b].hi; ++e) net += edges[e].sign;
    if (net != 0) out.emplace_back(net > 0 ? edges[b].lo : edges[b].hi, net > 0 ? edges[b].hi : edges[b].lo);
  }
  return out;
}

}  // namespace

int settle_face_points(QuantizedMesh& mesh, int bits, const std::vector<std::uint8_t>& candidates) {
  if (candidates.empty()) return 0;
  const std::int32_t top = static_cast<std::int32_t>((std::int64_t{1} << bits) - 1);
  const std::size_t n = mesh.positions.size() / 3;
  auto face_side = [&](std::size_t p, int a) {  // -1 low face, +1 high face, 0 neither
    const std::int32_t q = mesh.positions[3 * p + a];
    return q == 0 ? -1 : q == top ? 1 : 0;
  };
  // Only a candidate on a face can move: without one, no edge is counted.
  bool any_on_face = false;
  for (std::size_t p = 0; p < n && !any_on_face; ++p)
    any_on_face = candidates[p] && (face_side(p, 0) != 0 || face_side(p, 1) != 0 || face_side(p, 2) != 0);
  if (!any_on_face) return 0;
  // The axes along which both ends of u-v lie in one face plane.
  auto in_face = [&](std::uint32_t u, std::uint32_t v) {
    int axes = 0;
    for (int a = 0; a < 3; ++a)
      if (face_side(u, a) != 0 && face_side(u, a) == face_side(v, a)) axes |= 1 << a;
    return axes;
  };
  // held[p] bit a: p ends a boundary edge lying in its face plane along axis a.
  std::vector<std::uint8_t> held(n, 0), used(n, 0);
  for (std::uint32_t c : mesh.triangles) used[c] = 1;
  for (const auto& [u, v] : boundary_edges(mesh, [&](std::uint32_t a, std::uint32_t b) { return in_face(a, b) != 0; })) {
    const auto axes = static_cast<std::uint8_t>(in_face(u, v));
    held[u] |= axes, held[v] |= axes;
  }
  int moved = 0;
  for (std::size_t p = 0; p < n; ++p) {
    if (!used[p] || !candidates[p]) continue;
    bool any = false;
    for (int a = 0; a < 3; ++a) {
      const int side = face_side(p, a);
      if (side == 0 || (held[p] & (1 << a))) continue;
      mesh.positions[3 * p + a] -= 2 * side;  // two steps into the node
      any = true;
    }
    moved += any ? 1 : 0;
  }
  return moved;
}

}  // namespace keymesh::io::neuroglancer
