#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"

using namespace keymesh;

namespace {

// The relative error of the mean curvature against 1/r at every point.
std::vector<double> relative_errors(const SurfaceMesh& m, double r) {
  const Field* k = m.find_point_field("mean_curvature");
  EXPECT_NE(k, nullptr);
  std::vector<double> e;
  if (!k) return e;
  for (float v : k->values) e.push_back(std::abs(v * r - 1.0));
  std::sort(e.begin(), e.end());
  return e;
}

TEST(Curvature, SphereHasOneOverR) {
  for (double r : {20.5, 30.3}) {
    generate::ContourOptions o;
    o.isovalues = {r};
    o.curvature = true;
    const SurfaceMesh m = generate::contour(generate::spherical_distance(72), o);
    const auto e = relative_errors(m, r);
    ASSERT_FALSE(e.empty());
    EXPECT_LT(e[e.size() / 2], 0.02) << "median, r = " << r;
    EXPECT_LT(e[e.size() * 95 / 100], 0.05) << "95th percentile, r = " << r;
    // Carried through coarsening (averaged) and subdivision (interpolated).
    o.coarsen = true;
    const SurfaceMesh c = generate::contour(generate::spherical_distance(72), o);
    const auto ec = relative_errors(c, r);
    EXPECT_LT(ec[ec.size() / 2], 0.02);
    const SurfaceMesh s = generate::subdivide(c, generate::SubdivideOptions{});
    const auto es = relative_errors(s, r);
    EXPECT_LT(es[es.size() / 2], 0.02);
  }
}

TEST(Curvature, SignFollowsTheField) {
  // Values growing inward (a ball of high values): the curvature is -1/r.
  ImageGrid g = generate::spherical_distance(48);
  float* v = static_cast<float*>(g.data());
  for (Id p = 0; p < g.num_points(); ++p) v[p] = -v[p];
  generate::ContourOptions o;
  o.isovalues = {-20.5};
  o.curvature = true;
  const SurfaceMesh m = generate::contour(g, o);
  const Field* k = m.find_point_field("mean_curvature");
  ASSERT_NE(k, nullptr);
  std::vector<float> vals(k->values.begin(), k->values.end());
  std::sort(vals.begin(), vals.end());
  EXPECT_NEAR(vals[vals.size() / 2], -1 / 20.5, 0.02 / 20.5);
}

}  // namespace
