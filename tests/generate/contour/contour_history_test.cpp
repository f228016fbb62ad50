// ContourOptions::history (docs/HISTORY.md): the point field history_t and
// the keys through point_keys give every point back by the documented
// formula, whichever plan computed it (slabs: contour_stream_test.cpp).
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/generate/unstructured/contour_tets.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"

using namespace keymesh;
using generate::ContourOptions;

namespace {

ImageGrid sphere() {
  ImageGrid g = generate::spherical_distance(24);
  g.origin = {1.5, 2.25, 10.125};
  g.spacing = {0.5, 1.5, 0.3};
  return g;
}

ContourOptions with_history() {
  ContourOptions o;
  o.isovalues = {9.5, 4.25};
  o.history = true;
  return o;
}

// Every point's position from its key and history_t, by the formula of docs/HISTORY.md.
void expect_positions_given_back(const ImageGrid& g, const SurfaceMesh& m, const std::vector<std::uint64_t>& keys) {
  const Field* t = m.find_point_field("history_t");
  ASSERT_NE(t, nullptr);
  ASSERT_EQ(keys.size(), static_cast<std::size_t>(m.num_points()));
  const std::uint64_t nx = g.dims[0], ny = g.dims[1], n = nx * ny * static_cast<std::uint64_t>(g.dims[2]);
  for (Id p = 0; p < m.num_points(); ++p) {
    const std::uint64_t edge = keys[p] % (3 * n), point = edge / 3;
    const int axis = static_cast<int>(edge % 3);
    double u[3] = {double(point % nx), double(point / nx % ny), double(point / (nx * ny))};
    ASSERT_GE(t->values[p], 0.f);
    ASSERT_LE(t->values[p], 1.f);
    u[axis] += static_cast<double>(t->values[p]);
    for (int a = 0; a < 3; ++a)
      ASSERT_EQ(static_cast<float>(g.origin[a] + g.spacing[a] * u[a]), m.points[3 * p + a]) << "point " << p;
  }
}

TEST(ContourHistory, EveryPlanGivesEveryPointBack) {
  const ImageGrid g = sphere();
  ContourOptions o = with_history();
  std::vector<std::uint64_t> ref_keys;
  const SurfaceMesh ref = generate::contour(g, o, nullptr, &ref_keys);
  expect_positions_given_back(g, ref, ref_keys);
  for (auto weld : {generate::ContourWeld::KeyReduceSort, generate::ContourWeld::VertexWeld}) {
    o.weld = weld;
    std::vector<std::uint64_t> keys;
    const SurfaceMesh m = generate::contour(g, o, nullptr, &keys);
    expect_positions_given_back(g, m, keys);
  }
  // The history changes nothing else: the mesh without it is the same bytes.
  ContourOptions plain = with_history();
  plain.history = false;
  const SurfaceMesh bare = generate::contour(g, plain);
  ASSERT_EQ(bare.points.size(), ref.points.size());
  EXPECT_EQ(std::memcmp(bare.points.data(), ref.points.data(), bare.points.size() * sizeof(float)), 0);
  EXPECT_EQ(bare.connectivity, ref.connectivity);
}

TEST(ContourHistory, CoarseningAndOutputArraysAreRefused) {
  ContourOptions o = with_history();
  o.coarsen = true;
  EXPECT_THROW(generate::contour(sphere(), o), InputError);
  o.coarsen = false;
  o.output_arrays = [&](Id, Id) { return generate::ContourArrays{}; };
  EXPECT_THROW(generate::contour(sphere(), o), InputError);
}

TEST(ContourHistory, TetsKeyTheEdgeAndGiveThePointBack) {
  ImageGrid g = generate::spherical_distance(9);
  g.origin = {0.25, 1.5, 3.0};  // no coordinate near zero (docs/HISTORY.md)
  g.spacing = {0.3, 0.7, 1.1};
  const UnstructuredGrid tets = generate::tetrahedralize5(g);
  ContourOptions o = with_history();
  o.isovalues = {2.5, 3.25};
  std::vector<std::uint64_t> keys;
  const SurfaceMesh m = generate::contour(tets, o, nullptr, &keys);
  const Field* t = m.find_point_field("history_t");
  ASSERT_NE(t, nullptr);
  ASSERT_GT(m.num_points(), 100);
  ASSERT_EQ(keys.size(), static_cast<std::size_t>(m.num_points()));
  int b = 1;
  while ((std::uint64_t{1} << b) < static_cast<std::uint64_t>(tets.num_points())) ++b;
  const std::uint64_t mask = (std::uint64_t{1} << b) - 1;
  Id exact = 0;
  for (Id p = 0; p < m.num_points(); ++p) {
    const std::uint64_t a = (keys[p] >> b) & mask, c = keys[p] & mask;
    ASSERT_LT(a, c);
    bool same = true;
    for (int x = 0; x < 3; ++x) {
      const double pa = tets.points[3 * a + x], pc = tets.points[3 * c + x];
      same = same && static_cast<float>(pa + static_cast<double>(t->values[p]) * (pc - pa)) == m.points[3 * p + x];
    }
    exact += same;
  }
  // Two or three coordinates at once from one float t: nearly every point (docs/HISTORY.md).
  EXPECT_GE(exact * 100, m.num_points() * 97);
}

}  // namespace
