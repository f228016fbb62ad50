// The marching cubes case table, checked case by case against geometry:
// no two triangles of one cube cross, whatever the sample values.
#include "keymesh/generate/contour/marching_cubes_table.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "keymesh/analyze/self_intersections.hpp"
#include "keymesh/parallel/for_each.hpp"

using namespace keymesh;

namespace {

// How far each corner's sample is from the isovalue, inside (+) or outside
// (-): powers of two from 1/64 to 64, so a point sits at a fraction from
// 1/4097 to 4096/4097 of its edge, the middle included, and ratios between
// corners reach 4096 both ways; 1/2 and 2 put the ambiguous faces at and next
// to their balance (the diagonal corners' products equal or 4x apart).
constexpr std::array<float, 4> kDepths{1.0f / 64, 1.0f / 2, 2.0f, 64.0f};

struct Sweep {
  long configurations = 0;
  long crossing = 0;          // configurations with a crossing pair
  std::string first_example;  // values and pair of the first one met
};

// Every configuration of case `cube_case`: corner c's depth kDepths[digit c].
Sweep sweep_case(int cube_case) {
  const auto& t = generate::marching_cubes_table();
  Sweep s;
  const int n = t.triangle_count[cube_case];
  if (n < 2) return s;
  // Only the corners at an end of a cut edge move a point: the others stay at 1.
  std::array<bool, 8> moves{};
  for (const auto& ce : t.edges)
    if (((cube_case >> ce.corner0) & 1) != ((cube_case >> ce.corner1) & 1)) moves[ce.corner0] = moves[ce.corner1] = true;
  long total = 1;
  for (int c = 0; c < 8; ++c)
    if (moves[c]) total *= static_cast<long>(kDepths.size());
  for (long config = 0; config < total; ++config) {
    std::array<float, 8> value{};
    long rest = config;
    for (int c = 0; c < 8; ++c) {
      float d = 1;
      if (moves[c]) {
        d = kDepths[static_cast<std::size_t>(rest % static_cast<long>(kDepths.size()))];
        rest /= static_cast<long>(kDepths.size());
      }
      value[c] = ((cube_case >> c) & 1) ? d : -d;  // the isovalue is 0; inside is >= 0
    }
    // Points as the contour makes them: t from the first corner, in float.
    std::array<std::array<float, 3>, 12> point{};
    for (int e = 0; e < 12; ++e) {
      const auto& ce = t.edges[e];
      const float v0 = value[ce.corner0], v1 = value[ce.corner1];
      point[e] = {float(ce.dx), float(ce.dy), float(ce.dz)};
      point[e][ce.axis] += (0.0f - v0) / (v1 - v0);
    }
    auto tri = [&](int k) {
      const auto* te = &t.triangle_edges[cube_case][3 * k];
      return std::array<const float*, 3>{point[te[0]].data(), point[te[1]].data(), point[te[2]].data()};
    };
    ++s.configurations;
    bool crossed = false;
    for (int a = 0; a < n && !crossed; ++a)
      for (int b = a + 1; b < n && !crossed; ++b)
        if (analyze::triangles_cross(tri(a), tri(b))) {
          crossed = true;
          if (s.first_example.empty()) {
            std::ostringstream example;  // (not string +: GCC 12's -Wrestrict misfires on it)
            example << "triangles " << a << ", " << b << " at corner values";
            for (float v : value) example << ' ' << v;
            s.first_example = example.str();
          }
        }
    s.crossing += crossed;
  }
  return s;
}

}  // namespace

TEST(MarchingCubesTable, NoCaseHasCrossingTrianglesForAnySampleValues) {
  std::array<Sweep, 256> result;
  parallel::for_each_dynamic(256, [&](Id c) { result[c] = sweep_case(static_cast<int>(c)); }, 1);
  long configurations = 0;
  for (int c = 0; c < 256; ++c) {
    configurations += result[c].configurations;
    EXPECT_EQ(result[c].crossing, 0) << "case " << c << ": " << result[c].crossing << " of "
                                     << result[c].configurations << " configurations cross, first: "
                                     << result[c].first_example;
  }
  // The sweep ran: the cases with two triangles or more, most with every corner moving.
  EXPECT_GT(configurations, 8000000L);
}

// keymesh.dask (python/src/dask_contour_block.cpp) finds a triangle's cube
// from its corners' edges alone: along each axis, the least grid coordinate
// of the three edges' first points. That is the cube's own coordinate unless
// the three edges all lie on one face of the cube (none along that axis, all
// at the same offset): no triangle of either table does.
TEST(MarchingCubesTable, NoTriangleHasItsThreeEdgesOnOneFace) {
  for (bool reversed : {false, true}) {
    const auto& t = generate::marching_cubes_table(reversed);
    for (int c = 0; c < 256; ++c)
      for (int tri = 0; tri < t.triangle_count[c]; ++tri)
        for (int axis = 0; axis < 3; ++axis) {
          bool along = false;
          int lo = 1, hi = 0;
          for (int k = 0; k < 3; ++k) {
            const generate::CubeEdge& e = t.edges[t.triangle_edges[c][3 * tri + k]];
            const int offset = axis == 0 ? e.dx : (axis == 1 ? e.dy : e.dz);
            along = along || e.axis == axis;
            lo = std::min(lo, offset), hi = std::max(hi, offset);
          }
          EXPECT_TRUE(along || lo != hi) << "case " << c << " triangle " << tri << " axis " << axis << " reversed "
                                         << reversed;
        }
  }
}
