#pragma once
// One point's fans under split_nonmanifold's pairing rule (the rule is in
// include/keymesh/generate/coarsen/split_nonmanifold.hpp): its corners united
// through paired edges. Read by split_nonmanifold.cpp, which gathers the
// corners, rotates the pairings and renames the fans.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <vector>

#include "keymesh/core/equal_mask.hpp"
#include "keymesh/core/types.hpp"

namespace keymesh::generate::split_rule {

inline std::uint64_t edge_key(PointIndex a, PointIndex b) {
  return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
}

// A point's corners as the rule reads them: corner j's edge leaving the
// point ends at to[j], its edge arriving starts at from[j] (corners in
// increasing order; both arrays readable 4 past the last corner).
struct CornerEnds {
  const PointIndex* to;
  const PointIndex* from;
  Id d;
};
constexpr Id kEndsReadPast = 4;

// The local indices of the corners whose end in `ends` is w, in increasing
// order: the same triangles in the same order as seen from w, with the
// directions swapped.
inline void half_edges(const PointIndex* ends, Id d, PointIndex w, std::vector<std::uint32_t>& out) {
  out.clear();
  for (Id j = 0; j < d; ++j)
    if (ends[j] == w) out.push_back(static_cast<std::uint32_t>(j));
}

// A point's fans: labels[j] is the smallest local index of corner j's fan.
// Each edge's triangles are paired one each way, i-th up with i-th down (up
// from the smaller id to the larger), rotated by `rotation` for the edges
// of `multi` (ascending keys; rotation empty: none rotated yet).
struct FanRule {
  const std::vector<std::uint64_t>& multi;
  const std::vector<std::uint32_t>& rotation;

  std::uint32_t rotation_of(std::uint64_t key) const {
    if (rotation.empty()) return 0;
    const auto it = std::lower_bound(multi.begin(), multi.end(), key);
    return it != multi.end() && *it == key ? rotation[it - multi.begin()] : 0;
  }

  // `found` (when given) collects, from the smaller end, the edges with as
  // many triangles each way and at least two of each (in no set order).
  void operator()(PointIndex v, CornerEnds c, std::uint32_t* labels, std::vector<std::uint64_t>* found) const {
    for (Id j = 0; j < c.d; ++j) labels[j] = static_cast<std::uint32_t>(j);
    // Up to 64 corners, each fan's corners as a mask and every label kept at
    // its fan's smallest index (a union-find's path walks cost more); above,
    // a union-find whose root is the smallest index.
    const bool small = c.d <= kCornersMatched;
    std::uint64_t members[kCornersMatched];
    if (small)
      for (Id j = 0; j < c.d; ++j) members[j] = std::uint64_t{1} << j;
    auto find = [&](std::uint32_t x) {
      while (labels[x] != x) x = labels[x] = labels[labels[x]];
      return x;
    };
    auto unite = [&](std::uint32_t a, std::uint32_t b) {
      a = small ? labels[a] : find(a), b = small ? labels[b] : find(b);
      if (a == b) return;
      const std::uint32_t root = std::min(a, b), other = std::max(a, b);
      if (small) {
        for (std::uint64_t m = members[other]; m; m &= m - 1) labels[std::countr_zero(m)] = root;
        members[root] |= members[other];
      } else {
        labels[other] = root;
      }
    };
    // The corners whose edges join v and w, leaving and arriving, in
    // increasing local index: the labels do not depend on the order the
    // other ends come in (each root is its fan's smallest index).
    auto pair_up = [&](PointIndex w, const std::uint32_t* leaving, std::size_t n_leaving, const std::uint32_t* arriving,
                       std::size_t n_arriving) {
      if (w == v) {  // a triangle repeating v: its corners at v stay together
        for (std::size_t i = 0; i < n_arriving; ++i) unite(arriving[i], n_leaving ? leaving[0] : arriving[i]);
        for (std::size_t i = 0; i < n_leaving; ++i) unite(leaving[i], leaving[0]);
        return;
      }
      // Seen from the smaller end, "up" runs from the smaller id to the larger.
      const std::uint32_t* up = v < w ? leaving : arriving;
      const std::uint32_t* down = v < w ? arriving : leaving;
      const std::size_t n_up = v < w ? n_leaving : n_arriving, n_down = v < w ? n_arriving : n_leaving;
      const std::size_t pairs = std::min(n_up, n_down);
      const bool balanced = n_up == n_down && pairs >= 2;
      const std::uint64_t key = edge_key(v, w);
      const std::size_t rot = balanced ? rotation_of(key) : 0;
      if (balanced && found && v < w) found->push_back(key);
      for (std::size_t i = 0; i < pairs; ++i) unite(up[i], down[(i + rot) % n_down]);
    };
    if (small) {
      each_other_end_matched(c, pair_up);
      return;
    }
    each_other_end_sorted(c, pair_up);
    for (Id j = 0; j < c.d; ++j) labels[j] = find(static_cast<std::uint32_t>(j));
  }

 private:
  // Up to 64 corners (nearly every point), the corners of each other end
  // are found by comparing it with all the corners' ends at once, as bit
  // masks (the corners in increasing order, no sort: a sort per point cost
  // more than the rest of the rule).
  static constexpr Id kCornersMatched = 64;
  // Bit j set when ends[j] is w, for j < d (and maybe past d: masked).
  static std::uint64_t matching(const PointIndex* ends, Id d, PointIndex w) { return equal_mask(ends, d, w); }
  template <class F>
  static void each_other_end_matched(CornerEnds c, F&& pair_up) {
    const std::uint64_t all = c.d == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << c.d) - 1;
    std::uint64_t open_leaving = all, open_arriving = all;
    std::uint32_t leaving[kCornersMatched], arriving[kCornersMatched];
    auto listed = [](std::uint64_t m, std::uint32_t* out) {
      std::size_t n = 0;
      for (; m; m &= m - 1) out[n++] = static_cast<std::uint32_t>(std::countr_zero(m));
      return n;
    };
    while (open_leaving | open_arriving) {
      const PointIndex w = open_leaving ? c.to[std::countr_zero(open_leaving)] : c.from[std::countr_zero(open_arriving)];
      const std::uint64_t l = matching(c.to, c.d, w) & all, a = matching(c.from, c.d, w) & all;
      open_leaving &= ~l, open_arriving &= ~a;
      if (std::has_single_bit(l) && std::has_single_bit(a)) {  // nearly every edge: one pair
        leaving[0] = static_cast<std::uint32_t>(std::countr_zero(l));
        arriving[0] = static_cast<std::uint32_t>(std::countr_zero(a));
        pair_up(w, leaving, 1, arriving, 1);
        continue;
      }
      const std::size_t n_leaving = listed(l, leaving);
      pair_up(w, leaving, n_leaving, arriving, listed(a, arriving));
    }
  }
  // More: by a sort of (other end, arriving, local index). Scratch kept by
  // the calling thread.
  template <class F>
  static void each_other_end_sorted(CornerEnds c, F&& pair_up) {
    thread_local std::vector<std::uint64_t> ent;
    thread_local std::vector<std::uint32_t> leaving, arriving;
    ent.clear();
    for (Id j = 0; j < c.d; ++j) {
      ent.push_back((std::uint64_t{c.to[j]} << 32) | static_cast<std::uint64_t>(j));
      ent.push_back((std::uint64_t{c.from[j]} << 32) | (std::uint64_t{1} << 31) | static_cast<std::uint64_t>(j));
    }
    std::sort(ent.begin(), ent.end());
    for (std::size_t g = 0; g < ent.size();) {
      const PointIndex w = static_cast<PointIndex>(ent[g] >> 32);
      leaving.clear(), arriving.clear();
      for (; g < ent.size() && (ent[g] >> 32) == w; ++g)
        ((ent[g] >> 31) & 1 ? arriving : leaving).push_back(static_cast<std::uint32_t>(ent[g] & 0x7fffffffu));
      pair_up(w, leaving.data(), leaving.size(), arriving.data(), arriving.size());
    }
  }
};

}  // namespace keymesh::generate::split_rule
