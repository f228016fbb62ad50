#include "coincident_points.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <numeric>
#include <tuple>

namespace keymesh::io::neuroglancer {

namespace {

// Each point's representative: the first point with its position.
std::vector<std::uint32_t> first_at_position(const QuantizedMesh& mesh) {
  const std::size_t n = mesh.positions.size() / 3;
  auto at = [&](std::uint32_t i) {
    return std::tie(mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]);
  };
  std::vector<std::uint32_t> order(n), first(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return at(a) != at(b) ? at(a) < at(b) : a < b; });
  for (std::size_t k = 0; k < n; ++k)
    first[order[k]] = k > 0 && at(order[k]) == at(order[k - 1]) ? first[order[k - 1]] : order[k];
  return first;
}

// A triangle on three distinct points as a set (sorted) and its orientation
// relative to that order.
struct Corners {
  std::array<std::uint32_t, 3> set;
  int sign;
};

Corners corners(const std::uint32_t* t) {
  Corners c{{t[0], t[1], t[2]}, 1};
  // Sorting three items with swaps: each swap flips the orientation.
  auto swap_if = [&](int a, int b) {
    if (c.set[b] < c.set[a]) std::swap(c.set[a], c.set[b]), c.sign = -c.sign;
  };
  swap_if(0, 1), swap_if(1, 2), swap_if(0, 1);
  return c;
}

// 1 per triangle to keep: of the triangles on one set of points, the first
// |net orientation| of the winning orientation.
std::vector<char> cancel_opposite(const std::vector<Corners>& tris) {
  std::vector<std::uint32_t> order(tris.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return tris[a].set != tris[b].set ? tris[a].set < tris[b].set : a < b;
  });
  std::vector<char> keep(tris.size(), 0);
  for (std::size_t b = 0, e = 0; b < order.size(); b = e) {
    int net = 0;
    for (e = b; e < order.size() && tris[order[e]].set == tris[order[b]].set; ++e) net += tris[order[e]].sign;
    for (std::size_t j = b, left = static_cast<std::size_t>(std::abs(net)); j < e && left > 0; ++j)
      if ((tris[order[j]].sign > 0) == (net > 0)) keep[order[j]] = 1, --left;
  }
  return keep;
}

}  // namespace

std::vector<std::uint8_t> merge_coincident_points(QuantizedMesh& mesh) {
  const std::vector<std::uint32_t> first = first_at_position(mesh);
  bool merged = false;
  for (std::size_t i = 0; i < first.size() && !merged; ++i) merged = first[i] != i;
  if (!merged) return {};
  std::vector<std::uint8_t> in_group(first.size(), 0), touched(first.size(), 0);
  for (std::size_t i = 0; i < first.size(); ++i)
    if (first[i] != i) in_group[i] = in_group[first[i]] = 1;
  std::vector<std::array<std::uint32_t, 3>> tris;  // as written (their orientation), on merged points
  std::vector<Corners> sets;
  for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const std::array<std::uint32_t, 3> c{first[mesh.triangles[t]], first[mesh.triangles[t + 1]],
                                         first[mesh.triangles[t + 2]]};
    if (in_group[c[0]] || in_group[c[1]] || in_group[c[2]])
      for (std::uint32_t p : c) touched[p] = 1;
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;  // collapsed
    tris.push_back(c);
    sets.push_back(corners(c.data()));
  }
  const std::vector<char> keep = cancel_opposite(sets);
  std::vector<std::uint32_t> index(first.size(), 0), used(first.size(), 0);
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (keep[t])
      for (std::uint32_t c : tris[t]) used[c] = 1;
  QuantizedMesh out;
  std::vector<std::uint8_t> out_touched;
  for (std::size_t i = 0; i < first.size(); ++i) {
    if (!used[i]) continue;
    out_touched.push_back(touched[i]);
    index[i] = static_cast<std::uint32_t>(out.positions.size() / 3);
    out.positions.insert(out.positions.end(), mesh.positions.begin() + static_cast<std::ptrdiff_t>(3 * i),
                         mesh.positions.begin() + static_cast<std::ptrdiff_t>(3 * i + 3));
  }
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (keep[t])
      for (std::uint32_t c : tris[t]) out.triangles.push_back(index[c]);
  mesh = std::move(out);
  return out_touched;
}

}  // namespace keymesh::io::neuroglancer
