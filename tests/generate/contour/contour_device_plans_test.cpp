// The voxel contour's device plans (generate/contour/contour_device_plans.hpp)
// run on the CPU device equal contour() bit for bit: the structured plan the
// CPU's structured fast path (weld keyreduce), VERTEX-WELD the CPU's
// VERTEX-WELD (weld vertexweld), for every field option. (The sort plan's
// own cases are contour_device_test.cpp's; here it is reached by name.)
#include "keymesh/generate/contour/contour_device_plans.hpp"

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
using generate::DevicePlan;
using keymesh::testing::describe;
using keymesh::testing::integer_noise;
using keymesh::testing::noise;
using keymesh::testing::one_voxel_plate;
using keymesh::testing::thin_grids;
using keymesh::testing::with_nan_and_infinity;
using keymesh::testing::option_sets;

namespace {

std::string plan_name(DevicePlan plan) {
  return plan == DevicePlan::Structured ? "structured" : (plan == DevicePlan::Sort ? "sort" : "vertexweld");
}

// The structured and VERTEX-WELD plans against contour() with the weld each
// stands for (the sort plan has contour_device_test.cpp); VERTEX-WELD with
// 64-bit keys too when `wide`. Returns the triangles, for tests to check
// that they did contour.
Id expect_plans_equal_cpu(const ImageGrid& g, const std::vector<double>& isovalues, const std::string& what,
                          bool wide = false) {
  Id triangles = -1;
  for (ContourOptions opt : option_sets(isovalues)) {
    generate::ContourStats st;
    const SurfaceMesh fast = generate::contour(g, opt);
    const SurfaceMesh structured = generate::contour_plan_on_cpu_device(g, opt, DevicePlan::Structured, &st);
    keymesh::testing::expect_same_bits(structured, fast, describe(opt, what + " (structured)"));
    EXPECT_EQ(st.soup_points, 3 * fast.num_cells()) << what;
    opt.weld = ContourWeld::VertexWeld;
    const SurfaceMesh welded = generate::contour(g, opt);
    for (DeviceKeys keys : {DeviceKeys::Narrowest, DeviceKeys::Wide}) {
      if (keys == DeviceKeys::Wide && !wide) continue;
      const SurfaceMesh device = generate::contour_plan_on_cpu_device(g, opt, DevicePlan::VertexWeld, &st, keys);
      const std::string name = what + (keys == DeviceKeys::Wide ? " (vertexweld, 64-bit keys)" : " (vertexweld)");
      keymesh::testing::expect_same_bits(device, welded, describe(opt, name));
      EXPECT_EQ(st.key_bits, keys == DeviceKeys::Wide ? 64 : 32) << name;
    }
    triangles = fast.num_cells();
  }
  return triangles;
}

}  // namespace

TEST(DevicePlans, WeldChoosesItsPlan) {
  EXPECT_EQ(generate::device_plan_for(ContourWeld::KeyReduce), DevicePlan::Structured);
  EXPECT_EQ(generate::device_plan_for(ContourWeld::KeyReduceSort), DevicePlan::Sort);
  EXPECT_EQ(generate::device_plan_for(ContourWeld::VertexWeld), DevicePlan::VertexWeld);
}

TEST(DevicePlans, SpheresEqualTheCpu) {
  for (Id n : {33, 48}) {
    const ImageGrid g = generate::spherical_distance(n);
    EXPECT_GT(expect_plans_equal_cpu(g, {double(n) / 2 - 1 + 0.001}, "sphere paper iso", n == 33), 1000);
    EXPECT_GT(expect_plans_equal_cpu(g, {double(n) / 2 - 1.5, 7.25, 3.0}, "sphere three isovalues"), 1000);
  }
}

TEST(DevicePlans, NoiseEqualsTheCpu) {
  const ImageGrid g = noise(29, 23, 19, 7);
  EXPECT_GT(expect_plans_equal_cpu(g, {0.0}, "noise"), 5000);
  EXPECT_GT(expect_plans_equal_cpu(g, {-0.3, 0.45}, "noise two isovalues", true), 5000);
}

TEST(DevicePlans, IntegerSamplesOnTheIsovalueEqualTheCpu) {
  // Whole-number samples, many exactly on the isovalue (inside: value >= iso):
  // crossings at an edge's end, where VERTEX-WELD merges points of different edges.
  EXPECT_GT(expect_plans_equal_cpu(integer_noise<std::uint8_t>(24, 0, 6, 3, ScalarType::UInt8),
            {3.0}, "uint8", true), 1000);
  EXPECT_GT(expect_plans_equal_cpu(integer_noise<std::int16_t>(21, -4, 4, 5, ScalarType::Int16),
            {0.0, 2.0}, "int16"), 1000);
  EXPECT_GT(expect_plans_equal_cpu(integer_noise<std::int32_t>(19, -9, 9, 11, ScalarType::Int32),
            {-0.5}, "int32"), 1000);
  EXPECT_GT(expect_plans_equal_cpu(integer_noise<double>(18, 0, 3, 13, ScalarType::Float64), {1.0}, "float64"), 1000);
}

TEST(DevicePlans, NaNAndInfinitySamplesEqualTheCpu) {
  const ImageGrid g = with_nan_and_infinity(generate::spherical_distance(30));
  EXPECT_GT(expect_plans_equal_cpu(g, {11.5}, "NaN and inf"), 1000);
}

TEST(DevicePlans, ThinAndEmptyShapesEqualTheCpu) {
  for (const ImageGrid& g : thin_grids()) EXPECT_GT(expect_plans_equal_cpu(g, {0.1}, "thin grid"), 0);
  const ImageGrid plate = one_voxel_plate();
  EXPECT_GT(expect_plans_equal_cpu(plate, {100.0}, "one-voxel plate"), 100);
  // Integer isovalues past the type's range: no sample inside, or every one
  // (InsideTest's none / all), beside an isovalue that cuts.
  EXPECT_GT(expect_plans_equal_cpu(plate, {300.0, 100.0, -5.0}, "uint8 out of range"), 100);
  const ImageGrid sphere = generate::spherical_distance(20);
  EXPECT_EQ(expect_plans_equal_cpu(sphere, {1000.0}, "empty (none inside)"), 0);
  EXPECT_EQ(expect_plans_equal_cpu(sphere, {-1.0}, "empty (all inside)"), 0);
}

TEST(DevicePlans, ReversedAxesAndOffsetsEqualTheCpu) {
  const ImageGrid g = noise(17, 13, 11, 21);
  for (ContourOptions opt : option_sets({0.2, -0.4})) {
    opt.reversed_axes = true;
    opt.position_offset[0] = 5, opt.position_offset[1] = 7, opt.position_offset[2] = 9;
    const SurfaceMesh fast = generate::contour(g, opt);
    for (DevicePlan plan : {DevicePlan::Structured, DevicePlan::Sort})
      keymesh::testing::expect_same_bits(generate::contour_plan_on_cpu_device(g, opt, plan), fast,
                                         describe(opt, "reversed " + plan_name(plan)));
    opt.weld = ContourWeld::VertexWeld;
    keymesh::testing::expect_same_bits(generate::contour_plan_on_cpu_device(g, opt, DevicePlan::VertexWeld),
                                       generate::contour(g, opt), describe(opt, "reversed vertexweld"));
  }
}

TEST(DevicePlans, BitIdenticalAcrossThreadCounts) {
  const ImageGrid g = generate::spherical_distance(41);
  ContourOptions opt;
  opt.isovalues = {18.6, 9.5};
  opt.normals = ContourNormals::Average;
  for (DevicePlan plan : {DevicePlan::Structured, DevicePlan::VertexWeld}) {
    parallel::set_thread_count(1);
    const SurfaceMesh one = generate::contour_plan_on_cpu_device(g, opt, plan);
    for (int threads : {2, 3, 5}) {
      parallel::set_thread_count(threads);
      keymesh::testing::expect_same_bits(generate::contour_plan_on_cpu_device(g, opt, plan), one,
                                         "threads " + plan_name(plan));
    }
  }
  parallel::set_thread_count(0);
}

TEST(DevicePlans, RefuseWhatThePlansLackByName) {
  const ImageGrid g = generate::spherical_distance(8);
  ContourOptions opt;
  opt.isovalues = {2.5};
  opt.coarsen = true;
  for (DevicePlan plan : {DevicePlan::Structured, DevicePlan::Sort, DevicePlan::VertexWeld}) {
    try {
      generate::contour_plan_on_cpu_device(g, opt, plan);
      ADD_FAILURE() << "coarsening was not refused by the " << plan_name(plan) << " plan";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--coarsen"), std::string::npos) << e.what();
    }
  }
  opt.coarsen = false;
  opt.isovalues = {14.5};
  opt.max_output_bytes = 1000;  // checked before anything is sized
  for (DevicePlan plan : {DevicePlan::Structured, DevicePlan::Sort, DevicePlan::VertexWeld})
    EXPECT_THROW(generate::contour_plan_on_cpu_device(generate::spherical_distance(32), opt, plan), LimitError);
  opt.max_output_bytes = 0;
  opt.isovalues = {};
  EXPECT_THROW(generate::contour_plan_on_cpu_device(g, opt, DevicePlan::Structured), InputError);
}

TEST(DevicePlans, ResidentSamplesGiveTheUploadedMesh) {
  // contour_plan_arrays_on reads the samples through a view of the grid's
  // description (what cuda::contour_device hands it): the mesh equals the
  // upload entry's.
  const ImageGrid g = noise(15, 12, 10, 3);
  ImageGrid description;
  description.dims = g.dims, description.origin = g.origin, description.spacing = g.spacing;
  description.type = g.type, description.name = g.name;
  const device::CpuDevice d;
  for (ContourOptions opt : option_sets({0.1, -0.35})) {
    for (DevicePlan plan : {DevicePlan::Structured, DevicePlan::Sort, DevicePlan::VertexWeld}) {
      generate::ContourStats st;
      auto arrays = generate::contour_plan_arrays_on(d, description, g.data(), opt, plan, &st);
      EXPECT_GT(arrays.triangles, 100);
      const SurfaceMesh mesh =
          generate::device_contour::to_host_mesh(d, std::move(arrays), g.name, opt, st);
      keymesh::testing::expect_same_bits(mesh, generate::contour_plan_on_cpu_device(g, opt, plan),
                                         describe(opt, "resident " + plan_name(plan)));
    }
  }
  EXPECT_THROW(generate::contour_plan_arrays_on(d, description, nullptr, option_sets({0.1})[0], DevicePlan::Structured),
               InputError);
}
