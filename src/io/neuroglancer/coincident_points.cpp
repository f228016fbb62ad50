#include "coincident_points.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <limits>
#include <numeric>
#include <utility>

#include "keymesh/core/types.hpp"
#include "keymesh/keyreduce/groups.hpp"

namespace keymesh::io::neuroglancer {

namespace {

// Each point's representative: the first point with its position. One pass
// in point order over an open-addressing table of positions (at most half
// full): a position's slot holds the first point seen there, so no sort of
// the points (most nodes have no two on one position).
std::vector<std::uint32_t> first_at_position(const QuantizedMesh& mesh) {
  const std::size_t n = mesh.positions.size() / 3;
  const std::int32_t* at = mesh.positions.data();
  const int bits = std::max(1, static_cast<int>(std::bit_width(2 * n)));
  const std::size_t mask = (std::size_t{1} << bits) - 1;
  constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> slot(mask + 1, kEmpty), first(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t* p = at + 3 * i;
    std::uint64_t h = static_cast<std::uint32_t>(p[0]) * 0x9E3779B97F4A7C15ull;
    h = (h ^ static_cast<std::uint32_t>(p[1])) * 0xC2B2AE3D27D4EB4Full;
    h = (h ^ static_cast<std::uint32_t>(p[2])) * 0x165667B19E3779F9ull;
    std::size_t k = static_cast<std::size_t>(h >> (64 - bits));
    while (slot[k] != kEmpty && !std::equal(p, p + 3, at + 3 * static_cast<std::size_t>(slot[k]))) k = (k + 1) & mask;
    if (slot[k] == kEmpty) slot[k] = static_cast<std::uint32_t>(i);
    first[i] = slot[k];
  }
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

// 1 per triangle to keep from the triangles grouped by their set of points
// (`order`: the triangles by set, increasing within a set; `offsets`: where
// each set's begin): of the triangles on one set, the first |net
// orientation| of the winning orientation.
template <class Order, class Offsets>
std::vector<char> keep_net(const std::vector<Corners>& tris, const Order& order, const Offsets& offsets, std::size_t sets) {
  std::vector<char> keep(tris.size(), 0);
  for (std::size_t g = 0; g < sets; ++g) {
    const std::size_t b = static_cast<std::size_t>(offsets[g]), e = static_cast<std::size_t>(offsets[g + 1]);
    int net = 0;
    for (std::size_t j = b; j < e; ++j) net += tris[order[j]].sign;
    for (std::size_t j = b, left = static_cast<std::size_t>(std::abs(net)); j < e && left > 0; ++j)
      if ((tris[order[j]].sign > 0) == (net > 0)) keep[order[j]] = 1, --left;
  }
  return keep;
}

// keep_net's grouping: the sets packed into one key when the point numbers
// fit 21 bits (grouped by KEY-REDUCE), compared otherwise.
std::vector<char> cancel_opposite(const std::vector<Corners>& tris, std::size_t points) {
  const int bits = static_cast<int>(std::bit_width(points));
  if (bits <= 21) {
    std::vector<std::uint64_t> keys(tris.size());
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const auto& c = tris[t].set;
      keys[t] = static_cast<std::uint64_t>(c[0]) << (2 * bits) | static_cast<std::uint64_t>(c[1]) << bits | c[2];
    }
    const auto groups = keyreduce::partition_sort(std::move(keys), 3 * bits, keyreduce::Order::Build);
    return keep_net(tris, groups.order, groups.offsets, static_cast<std::size_t>(groups.num_groups()));
  }
  std::vector<std::uint32_t> order(tris.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return tris[a].set != tris[b].set ? tris[a].set < tris[b].set : a < b;
  });
  std::vector<std::size_t> offsets{0};
  for (std::size_t j = 1; j <= order.size(); ++j)
    if (j == order.size() || tris[order[j]].set != tris[order[j - 1]].set) offsets.push_back(j);
  return keep_net(tris, order, offsets, offsets.size() - 1);
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
  const std::vector<char> keep = cancel_opposite(sets, first.size());
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
