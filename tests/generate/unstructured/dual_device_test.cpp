// The dual's device path (generate/unstructured/dual_device.hpp) run on the
// CPU device equals dual(), the CPU path, bit for bit: points, fields,
// polygons and statistics, at 1 and several threads.
#include "keymesh/generate/unstructured/dual_device.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "keymesh/core/error.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/unstructured/dual.hpp"
#include "keymesh/parallel/threads.hpp"
#include "dual_cases.hpp"
#include "same_bits.hpp"
#include "uniform_noise.hpp"

using namespace keymesh;
using keymesh::testing::dual_sphere;

namespace {

void expect_same_stats(const generate::DualStats& a, const generate::DualStats& b, const std::string& what) {
  EXPECT_EQ(a.polygons, b.polygons) << what;
  EXPECT_EQ(a.boundary_fans, b.boundary_fans) << what;
  EXPECT_EQ(a.nonmanifold_points, b.nonmanifold_points) << what;
  EXPECT_EQ(a.skipped_fans, b.skipped_fans) << what;
}

// The device path equals the CPU path at 1 and 3 threads; returns the stats.
generate::DualStats expect_device_equals_cpu(const SurfaceMesh& m, const std::string& what) {
  generate::DualStats cpu_stats, device_stats;
  const SurfaceMesh cpu = generate::dual(m, &cpu_stats);
  for (int threads : {1, 3}) {
    parallel::set_thread_count(threads);
    const SurfaceMesh device = generate::dual_on_cpu_device(m, &device_stats);
    keymesh::testing::expect_same_bits(device, cpu, what + " threads " + std::to_string(threads));
    expect_same_stats(device_stats, cpu_stats, what);
  }
  parallel::set_thread_count(0);
  return cpu_stats;
}

// testing::open_grid_and_bowtie() (an open grid, a non-manifold point 9)
// and a point no cell uses (14); a NaN in a field.
SurfaceMesh open_grid_bowtie_and_fields() {
  SurfaceMesh m = keymesh::testing::open_grid_and_bowtie();
  m.points.insert(m.points.end(), {9, 9, 9});  // point 14
  Field f{"value", 2, Array<float>(2 * 15)};
  for (std::size_t i = 0; i < f.values.size(); ++i) f.values[i] = 0.3f * float(i) - 1.0f;
  f.values[7] = std::numeric_limits<float>::quiet_NaN();
  m.point_fields.push_back(std::move(f));
  return m;
}

}  // namespace

TEST(DeviceDual, ClosedSphereWithFieldsEqualsTheCpuPath) {
  // Normals (renormalised), scalars and curvature carried.
  const SurfaceMesh m = dual_sphere(24, 9.5);
  ASSERT_GT(m.num_cells(), 1000);
  const auto st = expect_device_equals_cpu(m, "sphere");
  EXPECT_EQ(st.polygons, m.num_points());
}

TEST(DeviceDual, DualOfTheDualEqualsTheCpuPath) {
  // Polygon input (offsets): the dual of a dual.
  const SurfaceMesh d = generate::dual(dual_sphere(16, 5.5));
  ASSERT_FALSE(d.all_triangles());
  expect_device_equals_cpu(d, "dual of the dual");
}

TEST(DeviceDual, OpenAndNonManifoldSurfacesEqualTheCpuPath) {
  const auto st = expect_device_equals_cpu(open_grid_bowtie_and_fields(), "open grid and bowtie");
  EXPECT_GT(st.boundary_fans, 0);
  EXPECT_GE(st.nonmanifold_points, 1);
  EXPECT_GT(st.skipped_fans, 0);
}

TEST(DeviceDual, OpenNoiseSurfaceEqualsTheCpuPath) {
  // A noise contour cut by the grid's faces: many boundary fans, a few
  // non-manifold points where the surface pinches.
  const ImageGrid g = keymesh::testing::uniform_noise({17, 15, 13}, 5);
  generate::ContourOptions o;
  o.isovalues = {0.2};
  o.normals = generate::ContourNormals::Gradient;
  const SurfaceMesh m = generate::contour(g, o);
  ASSERT_GT(m.num_cells(), 1000);
  const auto st = expect_device_equals_cpu(m, "noise");
  EXPECT_GT(st.boundary_fans, 0);
}

TEST(DeviceDual, EmptyAndSingleTriangleEqualTheCpuPath) {
  expect_device_equals_cpu(SurfaceMesh{}, "empty");
  SurfaceMesh one;
  one.points = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  one.connectivity = {0, 1, 2};
  one.point_fields.push_back(Field{"Normals", 3, {0, 0, 1, 0, 0, 1, 0, 0, -0.0f}});
  const auto st = expect_device_equals_cpu(one, "one triangle");
  EXPECT_EQ(st.skipped_fans, 3);
}

TEST(DeviceDual, RefusesWhatTheCpuRefuses) {
  SurfaceMesh bad;
  bad.points = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  bad.connectivity = {0, 1, 7};
  EXPECT_THROW(generate::dual(bad), InputError);
  EXPECT_THROW(generate::dual_on_cpu_device(bad), InputError);
}
