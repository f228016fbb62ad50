#include "keymesh/weld/vertex_weld.hpp"

#include <bit>
#include <cstring>
#include <limits>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh::weld {

namespace {

// Maps a float to an unsigned integer with the same order (and -0 to +0).
std::uint32_t sortable_bits(float f) {
  if (f == 0.0f) f = 0.0f;
  const std::uint32_t u = std::bit_cast<std::uint32_t>(f);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

}  // namespace

WeldResult vertex_weld(const float* soup_xyz, Id n) {
  if (n > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("VERTEX-WELD: " + std::to_string(n) + " points exceed 2^32 - 1");
  WeldResult result;
  // Lexicographic (x, y, z) order by three stable radix sorts: z, then y, then x.
  std::vector<std::uint32_t> perm(n), keys(n);
  parallel::for_each(n, [&](Id i) { perm[i] = static_cast<std::uint32_t>(i); });
  for (int axis = 2; axis >= 0; --axis) {
    parallel::for_each(n, [&](Id i) { keys[i] = sortable_bits(soup_xyz[3 * Id{perm[i]} + axis]); });
    parallel::sort_pairs(keys, perm, 32);
  }
  // Run heads: a point that differs from its predecessor in sorted order.
  std::vector<std::uint32_t> rank(n);
  auto same = [&](Id a, Id b) {
    const float* p = soup_xyz + 3 * a;
    const float* q = soup_xyz + 3 * b;
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
  };
  parallel::for_each(n, [&](Id i) { rank[i] = (i == 0 || !same(perm[i], perm[i - 1])) ? 1u : 0u; });
  std::vector<std::uint32_t> head(rank);
  const Id unique = parallel::exclusive_scan(rank.data(), rank.data(), n);
  result.points.resize(3 * unique);
  result.first.resize(unique);
  result.index_map.resize(n);
  parallel::for_each(n, [&](Id i) {
    const std::uint32_t r = head[i] ? rank[i] : rank[i] - 1;  // exclusive scan: heads take their own slot
    result.index_map[perm[i]] = r;
    if (head[i]) {
      result.first[r] = perm[i];  // stable sorts: the smallest soup index of the run comes first
      std::memcpy(&result.points[3 * Id{r}], soup_xyz + 3 * Id{perm[i]}, 3 * sizeof(float));
    }
  });
  return result;
}

}  // namespace keymesh::weld
