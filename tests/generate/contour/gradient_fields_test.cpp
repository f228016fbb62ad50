// Gradient normals and mean curvature of the structured plan's pass, which
// computes the derivatives at each grid point once for all the cut edges
// ending there (src/generate/contour/derivative_rows.hpp), against the formulas
// evaluated here point by point: central differences (one-sided at the
// border, 0 where not finite) at the edge's two ends, interpolated by t;
// Kindlmann's mean curvature from clamped central differences. Every point
// of the fine contour is checked bit for bit, on 8-bit, 16-bit and float
// samples (NaNs among them), with spacings that are and are not powers of
// two, on grids of several bricks (16 rows by 8 planes) whose surfaces reach
// every border, at 1 and 2 threads. The coarse pass is checked against
// coarsen() over the fine mesh for the same volumes.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/parallel/threads.hpp"

using namespace keymesh;
using generate::ContourNormals;
using generate::ContourOptions;
using generate::ContourWeld;

namespace {

// The grid's samples as doubles, and the derivatives the contour documents.
struct Reference {
  const ImageGrid& g;
  Id n[3];
  std::vector<double> v;

  explicit Reference(const ImageGrid& grid) : g(grid), n{grid.dims[0], grid.dims[1], grid.dims[2]} {
    v.resize(static_cast<std::size_t>(g.num_points()));
    for (Id p = 0; p < g.num_points(); ++p) v[p] = sample(p);
  }

  double sample(Id p) const {
    switch (g.type) {
      case ScalarType::UInt8: return static_cast<const std::uint8_t*>(g.data())[p];
      case ScalarType::Int16: return static_cast<const std::int16_t*>(g.data())[p];
      case ScalarType::Float32: return static_cast<const float*>(g.data())[p];
      default: return static_cast<const double*>(g.data())[p];
    }
  }
  Id id(const Id c[3]) const { return c[0] + n[0] * (c[1] + n[1] * c[2]); }

  // (v[c + 1] - v[c - 1]) / (2 h), one-sided at the border, 0 when not finite.
  void gradient(const Id c[3], double g_out[3]) const {
    for (int a = 0; a < 3; ++a) {
      Id lo[3] = {c[0], c[1], c[2]}, hi[3] = {c[0], c[1], c[2]};
      int neighbours = 0;
      if (c[a] > 0) --lo[a], ++neighbours;
      if (c[a] + 1 < n[a]) ++hi[a], ++neighbours;
      const double span = neighbours * g.spacing[a];
      const double dv = v[id(hi)] - v[id(lo)];
      g_out[a] = span > 0 && std::isfinite(dv) ? dv / span : 0.0;
    }
  }

  // Second differences with each index clamped to the grid, a non-finite
  // neighbour taken as the point's own value: xx, yy, zz, xy, xz, yz.
  void hessian(const Id c[3], double h[6]) const {
    const double f0 = v[id(c)];
    auto at = [&](int a, int da, int b, int db) {
      Id q[3] = {c[0], c[1], c[2]};
      if (q[a] + da >= 0 && q[a] + da < n[a]) q[a] += da;
      if (db != 0 && q[b] + db >= 0 && q[b] + db < n[b]) q[b] += db;
      const double x = v[id(q)];
      return std::isfinite(x) ? x : f0;
    };
    for (int a = 0; a < 3; ++a) h[a] = (at(a, 1, a, 0) - 2 * f0 + at(a, -1, a, 0)) / (g.spacing[a] * g.spacing[a]);
    const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (int p = 0; p < 3; ++p) {
      const int a = pairs[p][0], b = pairs[p][1];
      h[3 + p] = (at(a, 1, b, 1) - at(a, 1, b, -1) - at(a, -1, b, 1) + at(a, -1, b, -1)) /
                 (4 * g.spacing[a] * g.spacing[b]);
    }
  }
};

struct Expected {
  std::vector<float> normals, curvature;
};

// Every cut edge in key order (grid point, then axis), as the contour
// numbers its points: the point's normal (minus the interpolated gradient,
// unit) and mean curvature (|g|^2 tr H - g^T H g) / (2 |g|^3).
Expected expected_fields(const ImageGrid& grid, double iso) {
  const Reference r(grid);
  Expected e;
  for (Id k = 0; k < r.n[2]; ++k)
    for (Id j = 0; j < r.n[1]; ++j)
      for (Id i = 0; i < r.n[0]; ++i)
        for (int axis = 0; axis < 3; ++axis) {
          const Id c0[3] = {i, j, k};
          Id c1[3] = {i, j, k};
          if (++c1[axis] >= r.n[axis]) continue;
          const double v0 = r.v[r.id(c0)], v1 = r.v[r.id(c1)];
          if ((v0 >= iso) == (v1 >= iso)) continue;
          double t = (iso - v0) / (v1 - v0);
          t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.5;
          double g0[3], g1[3], h0[6], h1[6], g[3], h[6];
          r.gradient(c0, g0), r.gradient(c1, g1), r.hessian(c0, h0), r.hessian(c1, h1);
          for (int a = 0; a < 3; ++a) g[a] = g0[a] + t * (g1[a] - g0[a]);
          for (int a = 0; a < 6; ++a) h[a] = h0[a] + t * (h1[a] - h0[a]);
          const double len2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
          const double inv = len2 > 0 ? 1.0 / std::sqrt(len2) : 0.0;
          for (int a = 0; a < 3; ++a) e.normals.push_back(static_cast<float>(-g[a] * inv));
          const double hg[3] = {h[0] * g[0] + h[3] * g[1] + h[4] * g[2], h[3] * g[0] + h[1] * g[1] + h[5] * g[2],
                                h[4] * g[0] + h[5] * g[1] + h[2] * g[2]};
          const double ghg = g[0] * hg[0] + g[1] * hg[1] + g[2] * hg[2];
          const double kappa = (len2 * (h[0] + h[1] + h[2]) - ghg) / (2 * len2 * std::sqrt(len2));
          e.curvature.push_back(len2 > 0 && std::isfinite(kappa) ? static_cast<float>(kappa) : 0.f);
        }
  return e;
}

// A smooth field with noise over the grid's whole range of values, so the
// surface crosses every border; NaNs sprinkled in float grids.
ImageGrid volume(ScalarType type, std::array<Id, 3> dims, std::array<double, 3> spacing, unsigned seed) {
  ImageGrid g;
  g.allocate(dims, type);
  g.spacing = spacing;
  g.origin = {-1.5, 2.0, 0.25};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(-0.15, 0.15);
  for (Id p = 0; p < g.num_points(); ++p) {
    const Id i = p % dims[0], j = p / dims[0] % dims[1], k = p / (dims[0] * dims[1]);
    const double u = 0.5 + 0.3 * std::sin(0.23 * i) * std::cos(0.31 * j) + 0.2 * std::sin(0.4 * k) + noise(rng);
    switch (type) {
      case ScalarType::UInt8: static_cast<std::uint8_t*>(g.data())[p] = static_cast<std::uint8_t>(std::clamp(255 * u, 0.0, 255.0)); break;
      case ScalarType::Int16: static_cast<std::int16_t*>(g.data())[p] = static_cast<std::int16_t>(2000 * u - 1000); break;
      default:
        static_cast<float*>(g.data())[p] = p % 97 == 5 ? std::nanf("") : static_cast<float>(u);
    }
  }
  return g;
}

struct Case {
  ScalarType type;
  std::array<Id, 3> dims;
  std::array<double, 3> spacing;
  double iso;
};

const Case kCases[] = {
    {ScalarType::UInt8, {70, 37, 19}, {0.5, 0.5, 0.5}, 127.5},
    {ScalarType::UInt8, {66, 20, 11}, {0.3, 1.25, 2.0}, 140.2},
    {ScalarType::Int16, {65, 18, 17}, {1.0, 0.7, 0.25}, 3.5},
    {ScalarType::Float32, {67, 35, 18}, {0.5, 1.25, 2.0}, 0.5},
    {ScalarType::Float32, {3, 2, 2}, {1.1, 0.9, 4.0}, 0.45},
};

std::string name(const Case& c) {
  return std::string(scalar_type_name(c.type)) + " " + std::to_string(c.dims[0]) + "x" + std::to_string(c.dims[1]) +
         "x" + std::to_string(c.dims[2]);
}

bool same_bits(const Array<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), b.size() * sizeof(float)) == 0;
}

}  // namespace

TEST(GradientFields, StructuredPassEqualsTheFormulasAtEveryPoint) {
  for (const Case& c : kCases) {
    const ImageGrid g = volume(c.type, c.dims, c.spacing, 7);
    const Expected e = expected_fields(g, c.iso);
    ASSERT_GT(e.curvature.size(), c.dims[0] > 3 ? 1000u : 0u) << name(c);
    // Gradient normals alone, curvature alone, both: the pass caches
    // gradients alone in the first case, with second derivatives otherwise.
    for (int fields = 0; fields < 3; ++fields)
      for (int threads : {1, 2}) {
        parallel::set_thread_count(threads);
        ContourOptions o;
        o.isovalues = {c.iso};
        o.scalars = false;
        o.normals = fields != 1 ? ContourNormals::Gradient : ContourNormals::None;
        o.curvature = fields != 0;
        const SurfaceMesh m = generate::contour(g, o);
        const std::string what = name(c) + " fields " + std::to_string(fields) + " threads " + std::to_string(threads);
        ASSERT_EQ(m.num_points(), static_cast<Id>(e.curvature.size())) << what;
        if (fields != 1) {
          const Field* n = m.find_point_field("Normals");
          ASSERT_NE(n, nullptr) << what;
          EXPECT_TRUE(same_bits(n->values, e.normals)) << what;
        }
        if (fields != 0) {
          const Field* k = m.find_point_field("mean_curvature");
          ASSERT_NE(k, nullptr) << what;
          EXPECT_TRUE(same_bits(k->values, e.curvature)) << what;
        }
      }
  }
  parallel::set_thread_count(0);
}

// The coarse pass sums its crossings' fields as the fine points have them:
// the same bytes as coarsen() over the fine mesh (the sort plan's path).
TEST(GradientFields, CoarsePassEqualsCoarsenOverTheFineMesh) {
  for (const Case& c : kCases) {
    const ImageGrid g = volume(c.type, c.dims, c.spacing, 8);
    for (int fields = 0; fields < 3; ++fields) {
      ContourOptions o;
      o.isovalues = {c.iso, c.iso * 0.8};
      o.coarsen = true;
      o.scalars = fields == 2;
      o.normals = fields != 1 ? ContourNormals::Gradient : ContourNormals::None;
      o.curvature = fields != 0;
      o.weld = ContourWeld::KeyReduceSort;
      const SurfaceMesh sort = generate::contour(g, o);
      o.weld = ContourWeld::KeyReduce;
      for (int threads : {1, 2}) {
        parallel::set_thread_count(threads);
        const SurfaceMesh rows = generate::contour(g, o);
        const std::string what = name(c) + " fields " + std::to_string(fields) + " threads " + std::to_string(threads);
        EXPECT_EQ(rows.points, sort.points) << what;
        EXPECT_EQ(rows.connectivity, sort.connectivity) << what;
        ASSERT_EQ(rows.point_fields.size(), sort.point_fields.size()) << what;
        for (std::size_t f = 0; f < rows.point_fields.size(); ++f) {
          // Bit for bit (NaN included); an empty field's data() may be null, which memcmp may not get.
          const auto& a = rows.point_fields[f].values;
          const auto& b = sort.point_fields[f].values;
          ASSERT_EQ(a.size(), b.size()) << what << " " << rows.point_fields[f].name;
          EXPECT_TRUE(b.empty() || std::memcmp(a.data(), b.data(), b.size() * sizeof(float)) == 0)
              << what << " " << rows.point_fields[f].name;
        }
      }
    }
  }
  parallel::set_thread_count(0);
}
