// Subdivision's device path (generate/unstructured/subdivide_device.hpp) run on
// the CPU device equals subdivide(), the CPU path, bit for bit.
#include "keymesh/generate/unstructured/subdivide_device.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "keymesh/core/error.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "same_bits.hpp"
#include "uniform_noise.hpp"

using namespace keymesh;
using generate::SubdivideOptions;
using generate::SubdivideScheme;

namespace {

SurfaceMesh contour_of(const ImageGrid& g, double iso, generate::ContourNormals normals) {
  generate::ContourOptions o;
  o.isovalues = {iso};
  o.normals = normals;
  return generate::contour(g, o);
}

void expect_device_equals_cpu(const SurfaceMesh& m, const std::string& what) {
  for (auto scheme : {SubdivideScheme::Linear, SubdivideScheme::Bezier})
    for (int levels : {0, 1, 2}) {
      if (scheme == SubdivideScheme::Bezier && !m.find_point_field("Normals")) continue;
      SubdivideOptions o;
      o.levels = levels;
      o.scheme = scheme;
      const SurfaceMesh cpu = generate::subdivide(m, o);
      const SurfaceMesh device = generate::subdivide_on_cpu_device(m, o);
      keymesh::testing::expect_same_bits(device, cpu,
                                         what + " scheme " + std::to_string(int(scheme)) + " levels " +
                                             std::to_string(levels));
    }
}

}  // namespace

TEST(DeviceSubdivide, SphereWithFieldsEqualsTheCpuPath) {
  // Scalars and averaged normals carried (renormalised), both schemes.
  const SurfaceMesh m = contour_of(generate::spherical_distance(20), 7.5, generate::ContourNormals::Average);
  ASSERT_GT(m.num_cells(), 500);
  expect_device_equals_cpu(m, "sphere");
}

TEST(DeviceSubdivide, NoiseSurfaceWithCellFieldsEqualsTheCpuPath) {
  const ImageGrid g = keymesh::testing::uniform_noise({19, 17, 15}, 3);
  SurfaceMesh m = contour_of(g, 0.1, generate::ContourNormals::Gradient);
  Field cells{"cell_id", 2, Array<float>(static_cast<std::size_t>(2 * m.num_cells()))};
  for (std::size_t i = 0; i < cells.values.size(); ++i) cells.values[i] = 0.5f * float(i);
  m.cell_fields.push_back(std::move(cells));
  ASSERT_GT(m.num_cells(), 1000);
  expect_device_equals_cpu(m, "noise");
}

TEST(DeviceSubdivide, KeysNeeding64BitsEqualTheCpuPath) {
  // Over 2^16 points: an edge key (two point ids) needs more than 32 bits.
  const SurfaceMesh m = contour_of(generate::spherical_distance(132), 63.5, generate::ContourNormals::None);
  ASSERT_GT(m.num_points(), 1 << 16);
  SubdivideOptions o;
  keymesh::testing::expect_same_bits(generate::subdivide_on_cpu_device(m, o), generate::subdivide(m, o), "64-bit keys");
}

TEST(DeviceSubdivide, EmptyAndSingleTriangleEqualTheCpuPath) {
  SurfaceMesh empty;
  expect_device_equals_cpu(empty, "empty");
  SurfaceMesh one;
  one.points = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  one.connectivity = {0, 1, 2};
  one.point_fields.push_back(Field{"Normals", 3, {0, 0, 1, 0, 0, 1, 0, 0, 1}});
  one.point_fields.push_back(Field{"nan", 1, {std::numeric_limits<float>::quiet_NaN(), 1, -0.0f}});
  expect_device_equals_cpu(one, "one triangle");
}

TEST(DeviceSubdivide, RefusesWhatTheCpuRefuses) {
  SurfaceMesh bad;
  bad.points = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  bad.connectivity = {0, 1, 7};
  EXPECT_THROW(generate::subdivide_on_cpu_device(bad, SubdivideOptions{}), InputError);
  bad.connectivity = {0, 1, 2};
  SubdivideOptions o;
  o.scheme = SubdivideScheme::Bezier;  // no normals
  EXPECT_THROW(generate::subdivide_on_cpu_device(bad, o), InputError);
  o.scheme = SubdivideScheme::Linear;
  o.weld = generate::SubdivideWeld::VertexWeld;
  EXPECT_THROW(generate::subdivide_on_cpu_device(bad, o), InputError);
}

namespace {

// A grid's 5-tet split with a second point field and a cell field.
UnstructuredGrid tets_with_fields(const ImageGrid& grid) {
  UnstructuredGrid g = generate::tetrahedralize5(grid);
  Field p{"xz", 2, Array<float>(static_cast<std::size_t>(2 * g.num_points()))};
  for (Id i = 0; i < g.num_points(); ++i) p.values[2 * i] = g.points[3 * i], p.values[2 * i + 1] = -g.points[3 * i + 2];
  g.point_fields.push_back(std::move(p));
  Field c{"cell", 1, Array<float>(static_cast<std::size_t>(g.num_cells()))};
  for (Id i = 0; i < g.num_cells(); ++i) c.values[i] = 0.25f * float(i);
  g.cell_fields.push_back(std::move(c));
  return g;
}

}  // namespace

TEST(DeviceSubdivide, TetsEqualTheCpuPath) {
  ImageGrid sphere = generate::spherical_distance(7);
  sphere.spacing = {1.0, 0.5, 1.75};  // octahedra with distinct diagonals
  UnstructuredGrid g = tets_with_fields(sphere);
  for (int levels : {0, 1, 2}) {
    SubdivideOptions o;
    o.levels = levels;
    keymesh::testing::expect_same_bits(generate::subdivide_on_cpu_device(g, o), generate::subdivide(g, o),
                                       "tets levels " + std::to_string(levels));
  }
  // Left-handed input tets: children reoriented as on the CPU.
  for (Id t = 0; t < g.num_cells(); t += 3) {
    const std::uint64_t a = g.connectivity[4 * t];
    g.connectivity.set(static_cast<std::size_t>(4 * t), g.connectivity[4 * t + 1]);
    g.connectivity.set(static_cast<std::size_t>(4 * t + 1), a);
  }
  keymesh::testing::expect_same_bits(generate::subdivide_on_cpu_device(g, SubdivideOptions{}),
                                     generate::subdivide(g, SubdivideOptions{}), "left-handed tets");
}

TEST(DeviceSubdivide, TetKeysNeeding64BitsEqualTheCpuPath) {
  const UnstructuredGrid g = generate::tetrahedralize5(generate::spherical_distance(42));
  ASSERT_GT(g.num_points(), 1 << 16);
  keymesh::testing::expect_same_bits(generate::subdivide_on_cpu_device(g, SubdivideOptions{}),
                                     generate::subdivide(g, SubdivideOptions{}), "64-bit tet keys");
}

TEST(DeviceSubdivide, TetsRefuseWhatTheCpuRefuses) {
  const UnstructuredGrid g = generate::tetrahedralize5(generate::spherical_distance(4));
  SubdivideOptions o;
  o.scheme = SubdivideScheme::Bezier;
  EXPECT_THROW(generate::subdivide_on_cpu_device(g, o), InputError);
}
