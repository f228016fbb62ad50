// Array<T>: resize(n) and the size constructor leave elements unwritten (the
// output path's point: no zero fill before a generator's writes), while the
// value forms still fill, and an Array is otherwise a std::vector.
#include "keymesh/core/array.hpp"

#include <gtest/gtest.h>

#include <cstdint>

using keymesh::Array;

#ifndef KEYMESH_POISON_UNWRITTEN
TEST(Array, ResizeLeavesTheElementsUnwritten) {
  // Storage holding 7s, kept by resize(0): a std::vector's resize(n) writes
  // zeros over it, an Array's leaves the 7s.
  Array<std::uint32_t> v(1000, 7u);
  const std::uint32_t* storage = v.data();
  v.resize(0);
  v.resize(1000);
  ASSERT_EQ(v.data(), storage);
  for (std::uint32_t x : v) ASSERT_EQ(x, 7u);
}
#endif

TEST(Array, ValueFormsStillFill) {
  Array<float> v(1000, 1.5f);
  v.resize(0);
  v.resize(1000, 0.f);
  for (float x : v) ASSERT_EQ(x, 0.f);
  v.assign(10, 2.f);
  EXPECT_EQ(v, (Array<float>(10, 2.f)));
  v.push_back(3.f);
  EXPECT_EQ(v.size(), 11u);
  EXPECT_EQ(v.back(), 3.f);
}
