// ScalarType: sizes against the C++ types, names and parsing round-trip,
// and which types a grid may hold (visit_scalars' list).
#include <gtest/gtest.h>

#include <cstdint>

#include "keymesh/core/error.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/scalar_type.hpp"

namespace keymesh {
namespace {

TEST(ScalarType, SizesAreThoseOfTheCppTypes) {
  EXPECT_EQ(scalar_size(ScalarType::UInt8), sizeof(std::uint8_t));
  EXPECT_EQ(scalar_size(ScalarType::Int8), sizeof(std::int8_t));
  EXPECT_EQ(scalar_size(ScalarType::UInt16), sizeof(std::uint16_t));
  EXPECT_EQ(scalar_size(ScalarType::Int16), sizeof(std::int16_t));
  EXPECT_EQ(scalar_size(ScalarType::Int32), sizeof(std::int32_t));
  EXPECT_EQ(scalar_size(ScalarType::UInt32), sizeof(std::uint32_t));
  EXPECT_EQ(scalar_size(ScalarType::Int64), sizeof(std::int64_t));
  EXPECT_EQ(scalar_size(ScalarType::UInt64), sizeof(std::uint64_t));
  EXPECT_EQ(scalar_size(ScalarType::Float32), sizeof(float));
  EXPECT_EQ(scalar_size(ScalarType::Float64), sizeof(double));
}

TEST(ScalarType, GridTypesParseBackFromTheirNamesOthersAreRefused) {
  for (int i = 0; i <= static_cast<int>(ScalarType::UInt64); ++i) {
    const auto type = static_cast<ScalarType>(i);
    if (is_grid_scalar(type)) {
      EXPECT_EQ(parse_scalar_type(scalar_type_name(type)), type) << scalar_type_name(type);
      // visit_scalars hands out a pointer of the type's size.
      ImageGrid grid;
      grid.allocate({1, 1, 1}, type);
      EXPECT_EQ(visit_scalars(grid, [](const auto* p) { return sizeof(*p); }), scalar_size(type));
    } else {
      EXPECT_THROW(parse_scalar_type(scalar_type_name(type)), InputError) << scalar_type_name(type);
      ImageGrid grid;
      grid.type = type;
      EXPECT_THROW(visit_scalars(grid, [](const auto* p) { return sizeof(*p); }), InputError);
    }
  }
  EXPECT_TRUE(scalar_is_float(ScalarType::Float32));
  EXPECT_TRUE(scalar_is_float(ScalarType::Float64));
  EXPECT_FALSE(scalar_is_float(ScalarType::UInt64));
}

}  // namespace
}  // namespace keymesh
