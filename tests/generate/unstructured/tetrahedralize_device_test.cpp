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

void expect_same_grid(const UnstructuredGrid& device, const UnstructuredGrid& cpu, const std::string& what) {
  EXPECT_EQ(keymesh::testing::first_difference(device.points, cpu.points), "") << what;
  ASSERT_EQ(device.connectivity.wide(), cpu.connectivity.wide()) << what;
  if (cpu.connectivity.wide())
    EXPECT_EQ(keymesh::testing::first_difference(device.connectivity.wide_values(), cpu.connectivity.wide_values()), "")
        << what;
  else
    EXPECT_EQ(keymesh::testing::first_difference(device.connectivity.narrow(), cpu.connectivity.narrow()), "") << what;
  EXPECT_EQ(device.uniform_type, cpu.uniform_type);
  EXPECT_EQ(device.offsets, cpu.offsets);
  EXPECT_EQ(device.cell_types, cpu.cell_types);
  keymesh::testing::expect_same_fields(device.point_fields, cpu.point_fields, what + " point fields");
  keymesh::testing::expect_same_fields(device.cell_fields, cpu.cell_fields, what + " cell fields");
}

void expect_device_equals_cpu(const ImageGrid& grid, const std::string& what) {
  expect_same_grid(generate::tetrahedralize5_on_cpu_device(grid), generate::tetrahedralize5(grid), what + " (5 tets)");
  expect_same_grid(generate::tetrahedralize24_on_cpu_device(grid), generate::tetrahedralize24(grid),
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
