#pragma once
// The number of keyed pairs KEY-REDUCE numbers: its index map is 32-bit.
#include "keymesh/core/types.hpp"

namespace keymesh::keyreduce {

// Throws LimitError unless 0 <= n <= 2^32 - 1. partition_sort checks it
// first; a caller that copies the keys before (the Python module) checks it
// before the copy.
void check_pair_count(Id n);

}  // namespace keymesh::keyreduce
