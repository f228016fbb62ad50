// The voxel contour's device path (generate/contour/contour_device.hpp) run on
// the CPU device equals contour(), the CPU's fast path, bit for bit: the
// structured plan (the default) and the sort plan, for every field option.
#include "keymesh/generate/contour/contour_device.hpp"

#include <gtest/gtest.h>

#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/device/cpu_device.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/parallel/threads.hpp"
#include "device_contour_cases.hpp"
#include "same_bits.hpp"

using namespace keymesh;
using generate::ContourNormals;
using generate::ContourOptions;
using generate::ContourWeld;
using generate::DeviceKeys;
using keymesh::testing::describe;
using keymesh::testing::integer_noise;
using keymesh::testing::noise;
using keymesh::testing::one_voxel_plate;
using keymesh::testing::thin_grids;
using keymesh::testing::with_nan_and_infinity;
using keymesh::testing::option_sets;

namespace {

// The device path (narrow and wide keys) against both KEY-REDUCE plans of
// contour(); returns the triangles, for tests to check they did contour.
Id expect_device_equals_cpu(const ImageGrid& g, const std::vector<double>& isovalues, const std::string& what) {
  Id triangles = -1;
  for (ContourOptions opt : option_sets(isovalues)) {
    const SurfaceMesh fast = generate::contour(g, opt);
    opt.weld = ContourWeld::KeyReduceSort;
    const SurfaceMesh sorted = generate::contour(g, opt);
    opt.weld = ContourWeld::KeyReduce;
    generate::ContourStats st;
    const SurfaceMesh device = generate::contour_on_cpu_device(g, opt, &st);
    keymesh::testing::expect_same_bits(device, fast, describe(opt, what + " (structured plan)"));
    keymesh::testing::expect_same_bits(device, sorted, describe(opt, what + " (sort plan)"));
    EXPECT_EQ(st.soup_points, 3 * fast.num_cells()) << what;
    const SurfaceMesh wide = generate::contour_on_cpu_device(g, opt, &st, DeviceKeys::Wide);
    EXPECT_EQ(st.key_bits, 64);
    keymesh::testing::expect_same_bits(wide, fast, describe(opt, what + " (64-bit keys)"));
    triangles = fast.num_cells();
  }
  return triangles;
}

}  // namespace

TEST(DeviceContour, SpheresEqualTheCpuFastPath) {
  // Odd and even sizes, the paper's isovalue (a surface touching the box)
  // and a closed sphere; several isovalues at once.
  for (Id n : {33, 64}) {
    const ImageGrid g = generate::spherical_distance(n);
    EXPECT_GT(expect_device_equals_cpu(g, {double(n) / 2 - 1 + 0.001}, "sphere paper iso"), 1000);
    EXPECT_GT(expect_device_equals_cpu(g, {double(n) / 2 - 1.5, 7.25, 3.0}, "sphere three isovalues"), 1000);
  }
}

TEST(DeviceContour, NoiseEqualsTheCpuFastPath) {
  // Many small components, every cube case, non-unit spacing and origin.
  const ImageGrid g = noise(37, 29, 23, 7);
  EXPECT_GT(expect_device_equals_cpu(g, {0.0}, "noise"), 10000);
  EXPECT_GT(expect_device_equals_cpu(g, {-0.3, 0.45}, "noise two isovalues"), 10000);
}

TEST(DeviceContour, IntegerSamplesOnTheIsovalueEqualTheCpuFastPath) {
  // Whole-number samples, many exactly on the isovalue (inside: value >= iso).
  EXPECT_GT(expect_device_equals_cpu(integer_noise<std::uint8_t>(24, 0, 6, 3, ScalarType::UInt8),
            {3.0}, "uint8"), 1000);
  EXPECT_GT(expect_device_equals_cpu(integer_noise<std::int16_t>(21, -4, 4, 5, ScalarType::Int16), {0.0, 2.0}, "int16"),
            1000);
  EXPECT_GT(expect_device_equals_cpu(integer_noise<std::int32_t>(19, -9, 9, 11, ScalarType::Int32),
            {-0.5}, "int32"), 1000);
  EXPECT_GT(expect_device_equals_cpu(integer_noise<double>(18, 0, 3, 13, ScalarType::Float64), {1.0}, "float64"), 1000);
}

TEST(DeviceContour, NaNAndInfinitySamplesEqualTheCpuFastPath) {
  const ImageGrid g = with_nan_and_infinity(generate::spherical_distance(30));
  EXPECT_GT(expect_device_equals_cpu(g, {11.5}, "NaN and inf"), 1000);
}

TEST(DeviceContour, ThinAndEmptyShapesEqualTheCpuFastPath) {
  // One voxel thick grids, and a one-voxel plate inside a volume.
  const ImageGrid sphere = generate::spherical_distance(20);
  for (const ImageGrid& g : thin_grids()) EXPECT_GT(expect_device_equals_cpu(g, {0.1}, "thin grid"), 0);
  const ImageGrid plate = one_voxel_plate();
  EXPECT_GT(expect_device_equals_cpu(plate, {100.0}, "one-voxel plate"), 100);
  // Nothing inside, everything inside: empty meshes with the same (empty) fields.
  EXPECT_EQ(expect_device_equals_cpu(sphere, {1000.0}, "empty (none inside)"), 0);
  EXPECT_EQ(expect_device_equals_cpu(sphere, {-1.0}, "empty (all inside)"), 0);
}

TEST(DeviceContour, ReversedAxesAndOffsetsEqualTheCpuFastPath) {
  const ImageGrid g = noise(17, 13, 11, 21);
  for (ContourOptions opt : option_sets({0.2})) {
    opt.reversed_axes = true;
    opt.position_offset[0] = 5, opt.position_offset[1] = 7, opt.position_offset[2] = 9;
    const SurfaceMesh fast = generate::contour(g, opt);
    keymesh::testing::expect_same_bits(generate::contour_on_cpu_device(g, opt), fast, describe(opt, "reversed"));
  }
}

TEST(DeviceContour, BitIdenticalAcrossThreadCounts) {
  const ImageGrid g = generate::spherical_distance(41);
  ContourOptions opt;
  opt.isovalues = {18.6};
  opt.normals = ContourNormals::Average;
  parallel::set_thread_count(1);
  const SurfaceMesh one = generate::contour_on_cpu_device(g, opt);
  for (int threads : {2, 3, 5}) {
    parallel::set_thread_count(threads);
    keymesh::testing::expect_same_bits(generate::contour_on_cpu_device(g, opt), one, "threads");
  }
  parallel::set_thread_count(0);
}

TEST(DeviceContour, RefusesWhatThePathLacksByName) {
  const ImageGrid g = generate::spherical_distance(8);
  ContourOptions opt;
  opt.isovalues = {2.5};
  opt.weld = ContourWeld::VertexWeld;
  EXPECT_THROW(generate::contour_on_cpu_device(g, opt), InputError);
  opt.weld = ContourWeld::KeyReduce;
  opt.coarsen = true;  // the fine contour's entry refuses it (contour_coarsened_on coarsens)
  try {
    generate::contour_on(device::CpuDevice{}, g, opt, nullptr);
    ADD_FAILURE() << "coarsening was not refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--coarsen"), std::string::npos) << e.what();
  }
  opt.coarsen = false;
  opt.history = true;  // no history_t on this path: refused, not left out
  EXPECT_THROW(generate::contour_on_cpu_device(g, opt), InputError);
  opt.history = false;
  opt.isovalues = {};
  EXPECT_THROW(generate::contour_on_cpu_device(g, opt), InputError);  // contour()'s own input check
}

TEST(DeviceContour, OutputLimitIsCheckedBeforeSizing) {
  const ImageGrid g = generate::spherical_distance(32);
  ContourOptions opt;
  opt.isovalues = {14.5};
  opt.max_output_bytes = 1000;
  EXPECT_THROW(generate::contour_on_cpu_device(g, opt), LimitError);
}
