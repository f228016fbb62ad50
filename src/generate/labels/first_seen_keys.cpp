// Keys numbered in first-seen order (first_seen_keys.hpp).
#include "first_seen_keys.hpp"

#include <algorithm>
#include <bit>

namespace keymesh::generate::detail {

FirstSeenKeys first_seen_keys(const std::uint64_t* keys, Id n) {
  FirstSeenKeys f;
  const auto points = static_cast<std::size_t>(n);
  f.of_point.resize(points);
  f.keys.reserve(points), f.count.reserve(points), f.first.reserve(points);  // no regrowth
  // A power of two at least twice the points: probes stay short.
  const int bits = std::max(4, static_cast<int>(std::bit_width(static_cast<std::uint64_t>(2 * n))));
  const std::uint64_t mask = (std::uint64_t{1} << bits) - 1;
  std::vector<std::uint32_t> slot(static_cast<std::size_t>(mask + 1), 0);  // first-seen number + 1; 0: empty
  for (Id i = 0; i < n; ++i) {
    const std::uint64_t key = keys[i];
    const auto point = static_cast<std::uint32_t>(i);
    std::uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> (64 - bits);  // Fibonacci hashing: the high bits
    for (;; h = (h + 1) & mask) {
      const std::uint32_t s = slot[h];
      if (s == 0) {
        slot[h] = static_cast<std::uint32_t>(f.keys.size() + 1);
        f.of_point[point] = static_cast<std::uint32_t>(f.keys.size());
        f.keys.push_back(key);
        f.count.push_back(1);
        f.first.push_back(point);
        break;
      }
      if (f.keys[s - 1] == key) {
        f.of_point[point] = s - 1;
        ++f.count[s - 1];
        break;
      }
    }
  }
  return f;
}

}  // namespace keymesh::generate::detail
