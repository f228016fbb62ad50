// ScalarType: sizes against the C++ types, names and parsing round-trip,
// which types a grid may hold (visit_scalars' list), and a grid's range.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <limits>

#include "keymesh/core/error.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/label_scalars.hpp"
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

TEST(ScalarType, EveryTypeParsesBackWideLabelTypesOnlyThroughVisitAny) {
  for (int i = 0; i <= static_cast<int>(ScalarType::UInt64); ++i) {
    const auto type = static_cast<ScalarType>(i);
    EXPECT_EQ(parse_scalar_type(scalar_type_name(type)), type) << scalar_type_name(type);
    ImageGrid grid;
    grid.allocate({1, 1, 1}, type);
    // visit_any_scalars hands out a pointer of the type's size, every type.
    EXPECT_EQ(visit_any_scalars(grid, [](const auto* p) { return sizeof(*p); }), scalar_size(type));
    EXPECT_EQ(is_label_scalar(type), !scalar_is_float(type));
    if (is_grid_scalar(type)) {
      EXPECT_EQ(visit_scalars(grid, [](const auto* p) { return sizeof(*p); }), scalar_size(type));
    } else {  // the wide label types: the algorithms' visitor refuses them
      EXPECT_TRUE(is_label_scalar(type));
      EXPECT_THROW(visit_scalars(grid, [](const auto* p) { return sizeof(*p); }), InputError);
      EXPECT_NE(wide_samples_refusal(type).find("keymesh labels"), std::string::npos);
    }
  }
  EXPECT_THROW(parse_scalar_type("float16"), InputError);
  EXPECT_TRUE(scalar_is_float(ScalarType::Float32));
  EXPECT_TRUE(scalar_is_float(ScalarType::Float64));
  EXPECT_FALSE(scalar_is_float(ScalarType::UInt64));
}

// scalar_range: the extremes wherever they lie among the threads' chunks
// (grids past one chunk of 2^20 samples), NaN and infinities skipped, the
// range of a grid of nothing finite [0, 0].
TEST(ScalarType, RangeFindsTheExtremesInEveryChunkAndSkipsNonFinite) {
  const std::array<Id, 3> dims{128, 128, 130};  // 2,129,920 samples: three chunks
  const Id n = dims[0] * dims[1] * dims[2];
  for (const Id at : {Id{0}, n / 2 + 7, n - 1}) {
    ImageGrid bytes;
    bytes.allocate(dims, ScalarType::UInt8);
    auto* b = static_cast<std::uint8_t*>(bytes.data());
    for (Id i = 0; i < n; ++i) b[i] = static_cast<std::uint8_t>(40 + i % 100);
    b[at] = 3, b[(at + n / 3) % n] = 250;
    EXPECT_EQ(scalar_range(bytes), (std::array<double, 2>{3, 250})) << at;
    ImageGrid shorts;
    shorts.allocate(dims, ScalarType::Int16);
    auto* h = static_cast<std::int16_t*>(shorts.data());
    for (Id i = 0; i < n; ++i) h[i] = static_cast<std::int16_t>(i % 1000 - 500);
    h[at] = -30000;
    EXPECT_EQ(scalar_range(shorts), (std::array<double, 2>{-30000, 499})) << at;
    ImageGrid floats;
    floats.allocate(dims, ScalarType::Float32);
    auto* f = static_cast<float*>(floats.data());
    for (Id i = 0; i < n; ++i) f[i] = static_cast<float>(i % 77) * 0.5f;
    f[at] = std::numeric_limits<float>::quiet_NaN();
    f[(at + 1) % n] = -std::numeric_limits<float>::infinity();
    f[(at + n / 3) % n] = -2.25f;
    EXPECT_EQ(scalar_range(floats), (std::array<double, 2>{-2.25, 38})) << at;
  }
  ImageGrid nothing;
  nothing.allocate({2, 2, 1}, ScalarType::Float64);
  auto* d = static_cast<double*>(nothing.data());
  for (int i = 0; i < 4; ++i) d[i] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(scalar_range(nothing), (std::array<double, 2>{0, 0}));
}

}  // namespace
}  // namespace keymesh
