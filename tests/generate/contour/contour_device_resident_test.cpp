// The voxel contour's device-resident entry (contour_arrays_on: samples read
// where they lie, the mesh left as device arrays, mirror_back on the device)
// on the CPU device: what cuda::contour_device runs on the GPU, here held
// equal to the upload path (contour_on) and to the Python module's host
// mirroring, bit for bit.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/device/cpu_device.hpp"
#include "keymesh/generate/contour/contour_device.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "device_contour_cases.hpp"
#include "same_bits.hpp"

using namespace keymesh;
using generate::ContourNormals;
using generate::ContourOptions;
using generate::DeviceKeys;
using keymesh::testing::describe;
using keymesh::testing::noise;

namespace {

using Arrays = generate::device_contour::ContourArrays<device::CpuDevice>;

std::vector<ContourOptions> option_sets(const std::vector<double>& isovalues) {
  std::vector<ContourOptions> sets;
  for (auto normals : {ContourNormals::None, ContourNormals::Gradient, ContourNormals::Average})
    for (bool scalars : {true, false}) {
      ContourOptions opt;
      opt.isovalues = isovalues;
      opt.normals = normals;
      opt.scalars = scalars;
      opt.curvature = normals == ContourNormals::Gradient;
      sets.push_back(opt);
    }
  return sets;
}

// The grid's description without its samples (a DeviceVolume's grid): the
// entry must read them from the pointer it is given.
ImageGrid description_of(const ImageGrid& g) {
  ImageGrid d;
  d.dims = g.dims, d.origin = g.origin, d.spacing = g.spacing, d.type = g.type, d.name = g.name;
  return d;
}

Arrays resident_arrays(const ImageGrid& g, const ContourOptions& opt, generate::ContourStats* st = nullptr,
                       DeviceKeys keys = DeviceKeys::Narrowest) {
  return generate::contour_arrays_on(device::CpuDevice{}, description_of(g), g.data(), opt, st, keys);
}

SurfaceMesh to_host(Arrays&& a, const ImageGrid& g, const ContourOptions& opt) {
  generate::ContourStats st;
  return generate::device_contour::to_host_mesh(device::CpuDevice{}, std::move(a), g.name, opt, st);
}

// What the Python module's mirror_axes does to a host mesh of reversed axes:
// x <-> z in the points and every 3-component field, corners 1 and 2 swapped.
void mirror_on_host(SurfaceMesh& m) {
  for (Id p = 0; p < m.num_points(); ++p) {
    std::swap(m.points[3 * p], m.points[3 * p + 2]);
    for (Field& f : m.point_fields)
      if (f.components == 3) std::swap(f.values[3 * p], f.values[3 * p + 2]);
  }
  for (Id t = 0; t < m.num_cells(); ++t) std::swap(m.connectivity[3 * t + 1], m.connectivity[3 * t + 2]);
}

}  // namespace

TEST(DeviceContourResident, ViewOfTheSamplesEqualsTheUploadPath) {
  const ImageGrid sphere = generate::spherical_distance(23);
  const ImageGrid rough = noise(14, 11, 9, 5);
  for (const ImageGrid* g : {&sphere, &rough})
    for (const ContourOptions& opt : option_sets(g == &sphere ? std::vector<double>{4.5, 9.25} : std::vector<double>{0.1})) {
      const SurfaceMesh uploaded = generate::contour_on_cpu_device(*g, opt);
      ASSERT_GT(uploaded.num_cells(), 0);
      keymesh::testing::expect_same_bits(to_host(resident_arrays(*g, opt), *g, opt), uploaded, describe(opt, "view"));
      keymesh::testing::expect_same_bits(to_host(resident_arrays(*g, opt, nullptr, DeviceKeys::Wide), *g, opt),
                                         uploaded, describe(opt, "view, 64-bit keys"));
    }
}

TEST(DeviceContourResident, ArraysHoldTheMeshAndOnlyTheFieldsAsked) {
  const ImageGrid g = generate::spherical_distance(19);
  for (const ContourOptions& opt : option_sets({6.0})) {
    const SurfaceMesh mesh = generate::contour_on_cpu_device(g, opt);
    generate::ContourStats st;
    const Arrays a = resident_arrays(g, opt, &st);
    ASSERT_EQ(a.points, mesh.num_points());
    ASSERT_EQ(a.triangles, mesh.num_cells());
    EXPECT_EQ(a.xyz.size(), static_cast<std::size_t>(3 * a.points));
    EXPECT_EQ(a.connectivity.size(), static_cast<std::size_t>(3 * a.triangles));
    EXPECT_EQ(st.soup_points, 3 * a.triangles);
    const bool gradient = opt.normals == ContourNormals::Gradient, average = opt.normals == ContourNormals::Average;
    EXPECT_EQ(a.fields.scalar.size(), opt.scalars ? static_cast<std::size_t>(a.points) : 0u) << describe(opt, "");
    EXPECT_EQ(a.fields.gradient_normal.size(), gradient ? static_cast<std::size_t>(3 * a.points) : 0u);
    EXPECT_EQ(a.fields.curvature.size(), opt.curvature ? static_cast<std::size_t>(a.points) : 0u);
    EXPECT_EQ(a.fields.averaged_normal.size(), average ? static_cast<std::size_t>(3 * a.points) : 0u);
  }
}

TEST(DeviceContourResident, NoTriangleGivesEmptyArraysAndTheFieldsAsked) {
  const ImageGrid g = generate::spherical_distance(9);
  ContourOptions opt;
  opt.isovalues = {-1.0};  // every sample inside
  const SurfaceMesh m = to_host(resident_arrays(g, opt), g, opt);
  EXPECT_EQ(m.num_points(), 0);
  EXPECT_EQ(m.num_cells(), 0);
  keymesh::testing::expect_same_bits(m, generate::contour_on_cpu_device(g, opt), "empty");
}

TEST(DeviceContourResident, MirrorBackEqualsThePythonModulesHostMirroring) {
  const ImageGrid sphere = generate::spherical_distance(21);
  const ImageGrid rough = noise(12, 15, 10, 9);
  for (const ImageGrid* g : {&sphere, &rough})
    for (ContourOptions opt : option_sets(g == &sphere ? std::vector<double>{7.5} : std::vector<double>{-0.2, 0.3})) {
      opt.reversed_axes = true;  // the grid is a C-ordered array's axes reversed
      SurfaceMesh expected = generate::contour(*g, opt);
      ASSERT_GT(expected.num_cells(), 0);
      mirror_on_host(expected);
      Arrays a = resident_arrays(*g, opt);
      generate::mirror_back(device::CpuDevice{}, a);
      keymesh::testing::expect_same_bits(to_host(std::move(a), *g, opt), expected, describe(opt, "mirrored"));
    }
}

TEST(DeviceContourResident, RefusesNullSamplesAndWhatThePathLacks) {
  const ImageGrid g = generate::spherical_distance(8);
  ContourOptions opt;
  opt.isovalues = {3.0};
  EXPECT_THROW(generate::contour_arrays_on(device::CpuDevice{}, description_of(g), nullptr, opt, nullptr), InputError);
  ContourOptions weld = opt;
  weld.weld = generate::ContourWeld::VertexWeld;
  try {
    resident_arrays(g, weld);
    FAIL() << "VERTEX-WELD accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("VERTEX-WELD"), std::string::npos) << e.what();
  }
  ContourOptions none = opt;
  none.isovalues.clear();
  EXPECT_THROW(resident_arrays(g, none), InputError);
  ImageGrid flat = description_of(g);
  flat.dims[2] = 1;
  EXPECT_THROW(generate::contour_arrays_on(device::CpuDevice{}, flat, g.data(), opt, nullptr), InputError);
}

TEST(DeviceContourResident, StageTimesComeFromTheDevicesClock) {
  const ImageGrid g = generate::spherical_distance(40);
  ContourOptions opt;
  opt.isovalues = {12.0};
  opt.normals = ContourNormals::Average;
  generate::ContourStats st;
  st.classify = 99;  // reset by the entry, then measured
  resident_arrays(g, opt, &st);
  EXPECT_GT(st.classify, 0.0);
  EXPECT_LT(st.classify, 99.0);
  EXPECT_GT(st.generate, 0.0);
  EXPECT_GT(st.weld, 0.0);
  EXPECT_GT(st.fields, 0.0);
}
