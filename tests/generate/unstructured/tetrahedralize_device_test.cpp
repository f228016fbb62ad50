// The tetrahedralizations' device paths
// (generate/unstructured/tetrahedralize_device.hpp) run on the CPU device equal
// tetrahedralize5(grid) and tetrahedralize24(grid), the CPU paths, bit for bit.
#include "keymesh/generate/unstructured/tetrahedralize_device.hpp"

#include <gtest/gtest.h>

#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "same_bits.hpp"

using namespace keymesh;

namespace {

void expect_device_equals_cpu(const ImageGrid& grid, const std::string& what) {
  keymesh::testing::expect_same_bits(generate::tetrahedralize5_on_cpu_device(grid), generate::tetrahedralize5(grid),
                                     what + " (5 tets)");
  keymesh::testing::expect_same_bits(generate::tetrahedralize24_on_cpu_device(grid), generate::tetrahedralize24(grid),
                                     what + " (24 tets)");
}

}  // namespace

TEST(DeviceTetrahedralize, FiveAndTwentyFourTetsOfGridsEqualTheCpuPath) {
  ImageGrid sphere = generate::spherical_distance(13);
  sphere.origin = {1.5, -2, 0.25};
  sphere.spacing = {0.5, 1.5, 2};
  expect_device_equals_cpu(sphere, "sphere");
  sphere.spacing = {0.5, -1.5, 2};  // mirrored: two corners of every tet swapped
  expect_device_equals_cpu(sphere, "mirrored");
  ImageGrid thin;
  thin.allocate({2, 7, 5}, ScalarType::Int16);
  auto* v = static_cast<std::int16_t*>(thin.data());
  for (Id i = 0; i < thin.num_points(); ++i) v[i] = static_cast<std::int16_t>(i * 37 - 900);
  expect_device_equals_cpu(thin, "thin int16");
}

TEST(DeviceTetrahedralize, RefusesWhatTheCpuRefuses) {
  ImageGrid flat;
  flat.allocate({4, 1, 4}, ScalarType::Float32);
  EXPECT_THROW(generate::tetrahedralize5_on_cpu_device(flat), InputError);
  EXPECT_THROW(generate::tetrahedralize24_on_cpu_device(flat), InputError);
}
