// free_storage gives the storage back; `v = {}`, which it replaces, keeps it.
#include "keymesh/core/free_storage.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

TEST(FreeStorage, ReleasesTheCapacityThatBraceAssignmentKeeps) {
  std::vector<std::uint64_t> kept(1000, 7), freed(1000, 7);
  kept = {};
  keymesh::free_storage(freed);
  EXPECT_TRUE(kept.empty());
  EXPECT_GE(kept.capacity(), 1000u);  // why free_storage exists
  EXPECT_TRUE(freed.empty());
  EXPECT_EQ(freed.capacity(), 0u);
}
