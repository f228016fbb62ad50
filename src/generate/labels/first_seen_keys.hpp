// The distinct keys of a small input (a chunk piece's points, a face's cut)
// numbered in first-seen order by an open-addressing hash table: grouping
// without sorting the (key, index) pairs, whose comparisons branch at
// random. Callers that need the groups in key order sort only the distinct
// keys (label_coarsen.cpp); a group's first point is its least index
// (label_face_clusters.cpp).
#pragma once

#include <cstdint>
#include <vector>

#include "keymesh/core/types.hpp"

namespace keymesh::generate::detail {

struct FirstSeenKeys {
  std::vector<std::uint64_t> keys;      // per first-seen number
  std::vector<std::uint32_t> count;     // per first-seen number: its points
  std::vector<std::uint32_t> first;     // per first-seen number: its least point index
  std::vector<std::uint32_t> of_point;  // per point: its key's first-seen number
};

// n below 2^31 (the callers' inputs are far smaller).
FirstSeenKeys first_seen_keys(const std::uint64_t* keys, Id n);

}  // namespace keymesh::generate::detail
