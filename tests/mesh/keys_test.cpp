// mesh/keys: edge and quad-face keys of unstructured meshes.
#include <gtest/gtest.h>

#include <set>

#include "keymesh/core/error.hpp"
#include "keymesh/mesh/keys.hpp"

namespace keymesh {
namespace {

TEST(Keys, EdgeKeysAreUnorderedDecodableAndDistinct) {
  const EdgeKeys ek = EdgeKeys::for_points(37, "test");
  EXPECT_EQ(ek.bits, 6);  // ids 0..36 need 6 bits
  std::set<std::uint64_t> seen;
  for (std::uint64_t a = 0; a < 37; ++a)
    for (std::uint64_t b = a + 1; b < 37; ++b) {
      const std::uint64_t k = ek(a, b);
      EXPECT_EQ(k, ek(b, a));
      EXPECT_LT(k, std::uint64_t{1} << ek.key_bits());
      EXPECT_EQ(ek.decode(k), std::make_pair(a, b));
      EXPECT_TRUE(seen.insert(k).second);
      const std::uint64_t leveled = ek.with_level(k, 5);
      EXPECT_EQ(ek.level(leveled), 5u);
      EXPECT_EQ(ek.decode(leveled), std::make_pair(a, b));
    }
}

TEST(Keys, QuadKeyIsTheSameFromEitherSideAndAnyStartingCorner) {
  const EdgeKeys ek = EdgeKeys::for_points(100, "test");
  const std::uint64_t face[4] = {41, 7, 90, 12};
  const std::uint64_t k = ek.quad(face);
  EXPECT_EQ(ek.decode(k), std::make_pair(std::uint64_t{7}, std::uint64_t{12}));
  for (int start = 0; start < 4; ++start) {
    std::uint64_t rotated[4], reversed[4];
    for (int i = 0; i < 4; ++i) {
      rotated[i] = face[(start + i) % 4];
      reversed[i] = face[(start + 4 - i) % 4];
    }
    EXPECT_EQ(ek.quad(rotated), k);
    EXPECT_EQ(ek.quad(reversed), k);
  }
}

TEST(Keys, TooManyPointsAreRefusedByName) {
  EXPECT_NO_THROW(EdgeKeys::for_points(Id{1} << 32, "test"));
  try {
    EdgeKeys::for_points((Id{1} << 32) + 1, "subdivide");
    FAIL() << "no throw";
  } catch (const LimitError& e) {
    EXPECT_NE(std::string(e.what()).find("subdivide"), std::string::npos);
  }
}

}  // namespace
}  // namespace keymesh
