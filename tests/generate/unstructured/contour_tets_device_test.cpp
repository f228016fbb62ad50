// Marching tetrahedra's device path (generate/unstructured/contour_tets_device.hpp)
// run on the CPU device equals contour(tets), the CPU path, bit for bit.
#include "keymesh/generate/unstructured/contour_tets_device.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "same_bits.hpp"
#include "tet_grid_cases.hpp"

using namespace keymesh;
using keymesh::testing::tet_noise;
using keymesh::testing::tets_of;
using generate::ContourNormals;
using generate::ContourOptions;

namespace {

// The device path against contour(tets) for each normal option, with and
// without the scalars; returns the triangles.
Id expect_device_equals_cpu(const UnstructuredGrid& g, const std::vector<double>& isovalues, const std::string& what) {
  Id triangles = -1;
  for (auto normals : {ContourNormals::None, ContourNormals::Average})
    for (bool scalars : {true, false}) {
      ContourOptions o;
      o.isovalues = isovalues;
      o.normals = normals;
      o.scalars = scalars;
      generate::ContourStats st;
      const SurfaceMesh cpu = generate::contour(g, o);
      const SurfaceMesh device = generate::contour_tets_on_cpu_device(g, o, &st);
      keymesh::testing::expect_same_bits(device, cpu, what + " normals " + std::to_string(int(normals)));
      EXPECT_EQ(st.soup_points, 3 * cpu.num_cells());
      triangles = cpu.num_cells();
    }
  return triangles;
}

}  // namespace

TEST(DeviceTets, SphereEqualsTheCpuPath) {
  const UnstructuredGrid g = tets_of(generate::spherical_distance(18));
  EXPECT_GT(expect_device_equals_cpu(g, {7.3}, "sphere"), 500);
  EXPECT_GT(expect_device_equals_cpu(g, {3.5, 7.3}, "sphere two isovalues"), 500);
}

TEST(DeviceTets, NoiseAndLeftHandedTetsEqualTheCpuPath) {
  UnstructuredGrid g = tets_of(tet_noise(11, 4));
  EXPECT_GT(expect_device_equals_cpu(g, {0.0}, "noise"), 1000);
  // Every other tet mirrored (two corners swapped): its triangles are wound back.
  for (Id t = 0; t < g.num_cells(); t += 2) {
    const std::uint64_t a = g.connectivity[4 * t + 2];
    g.connectivity.set(static_cast<std::size_t>(4 * t + 2), g.connectivity[4 * t + 3]);
    g.connectivity.set(static_cast<std::size_t>(4 * t + 3), a);
  }
  EXPECT_GT(expect_device_equals_cpu(g, {0.2}, "noise, left-handed tets"), 1000);
}

TEST(DeviceTets, IntegerSamplesOnTheIsovalueAndNaNEqualTheCpuPath) {
  ImageGrid grid;
  grid.allocate({9, 10, 11}, ScalarType::Float32);
  float* v = static_cast<float*>(grid.data());
  std::mt19937 rng(8);
  for (Id i = 0; i < grid.num_points(); ++i) v[i] = float(rng() % 5);  // many samples exactly 2
  EXPECT_GT(expect_device_equals_cpu(tets_of(grid), {2.0}, "integers on the isovalue"), 100);
  for (Id i = 0; i < grid.num_points(); i += 6)
    v[i] = i % 12 ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
  EXPECT_GT(expect_device_equals_cpu(tets_of(grid), {1.5}, "NaN and inf"), 100);
}

TEST(DeviceTets, ThinAndEmptyEqualTheCpuPath) {
  ImageGrid thin;
  thin.allocate({12, 9, 2}, ScalarType::Float32);
  float* v = static_cast<float*>(thin.data());
  for (Id i = 0; i < thin.num_points(); ++i) v[i] = float(std::cos(0.9 * double(i)));
  EXPECT_GT(expect_device_equals_cpu(tets_of(thin), {0.0}, "thin"), 10);
  EXPECT_EQ(expect_device_equals_cpu(tets_of(thin), {5.0}, "empty"), 0);
}

TEST(DeviceTets, KeysNeeding64BitsEqualTheCpuPath) {
  // Over 2^16 points: an edge key needs more than 32 bits.
  const UnstructuredGrid g = tets_of(generate::spherical_distance(42));
  ASSERT_GT(g.num_points(), 1 << 16);
  EXPECT_GT(expect_device_equals_cpu(g, {19.5}, "64-bit keys"), 1000);
}

TEST(DeviceTets, RefusesOutOfRangeIdsAsTheCpuDoes) {
  UnstructuredGrid g = tets_of(generate::spherical_distance(6));
  g.connectivity.set(41, 1000000);
  ContourOptions o;
  o.isovalues = {2.5};
  std::string cpu, device;
  try {
    generate::contour(g, o);
  } catch (const InputError& e) {
    cpu = e.what();
  }
  try {
    generate::contour_tets_on_cpu_device(g, o);
  } catch (const InputError& e) {
    device = e.what();
  }
  EXPECT_NE(cpu, "");
  EXPECT_EQ(device, cpu);
}
