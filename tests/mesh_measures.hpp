#pragma once
// Measures of test meshes computed independently of the library.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <vector>

#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/parallel/threads.hpp"

namespace keymesh::test {

// Signed volume enclosed by a closed triangle mesh (divergence theorem):
// positive when the triangles face outward.
inline double enclosed_volume(const SurfaceMesh& m) {
  double v = 0;
  for (Id t = 0; t < m.num_cells(); ++t) {
    const float* a = &m.points[3 * m.connectivity[3 * t]];
    const float* b = &m.points[3 * m.connectivity[3 * t + 1]];
    const float* c = &m.points[3 * m.connectivity[3 * t + 2]];
    v += (double(a[0]) * (double(b[1]) * c[2] - double(b[2]) * c[1]) -
          double(a[1]) * (double(b[0]) * c[2] - double(b[2]) * c[0]) +
          double(a[2]) * (double(b[0]) * c[1] - double(b[1]) * c[0])) / 6.0;
  }
  return v;
}

// The points as coordinate triples, sorted: compares meshes up to renumbering.
inline std::vector<std::array<float, 3>> sorted_points(const SurfaceMesh& m) {
  std::vector<std::array<float, 3>> p(static_cast<std::size_t>(m.num_points()));
  for (Id i = 0; i < m.num_points(); ++i) p[i] = {m.points[3 * i], m.points[3 * i + 1], m.points[3 * i + 2]};
  std::sort(p.begin(), p.end());
  return p;
}

// Triangles as position triples rotated to start at the smallest corner
// (winding kept), sorted: compares meshes up to renumbering.
inline std::vector<std::array<std::array<float, 3>, 3>> triangle_set(const SurfaceMesh& m) {
  std::vector<std::array<std::array<float, 3>, 3>> tris(static_cast<std::size_t>(m.num_cells()));
  for (Id t = 0; t < m.num_cells(); ++t) {
    for (int c = 0; c < 3; ++c) {
      const Id p = m.connectivity[3 * t + c];
      tris[t][c] = {m.points[3 * p], m.points[3 * p + 1], m.points[3 * p + 2]};
    }
    std::rotate(tris[t].begin(), std::min_element(tris[t].begin(), tris[t].end()), tris[t].end());
  }
  std::sort(tris.begin(), tris.end());
  return tris;
}

// f() run with `threads` worker threads, then all cores again.
template <class F>
auto at_threads(int threads, F&& f) {
  parallel::set_thread_count(threads);
  auto result = f();
  parallel::set_thread_count(0);
  return result;
}

// Every byte of the two meshes' points, cells and point fields equal (the
// same output at another thread count).
inline void expect_identical(const SurfaceMesh& a, const SurfaceMesh& b) {
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.connectivity, b.connectivity);
  ASSERT_EQ(a.point_fields.size(), b.point_fields.size());
  for (std::size_t i = 0; i < a.point_fields.size(); ++i) EXPECT_EQ(a.point_fields[i].values, b.point_fields[i].values);
}

// run(by_position) at 1 and 4 threads gives the same bytes, and welding by
// position (VERTEX-WELD) the same points and triangles up to renumbering.
// Returns the 1-thread mesh.
template <class Run>
SurfaceMesh expect_threads_and_vertex_weld_agree(Run&& run) {
  const SurfaceMesh one = at_threads(1, [&] { return run(false); });
  const SurfaceMesh four = at_threads(4, [&] { return run(false); });
  const SurfaceMesh welded = run(true);
  expect_identical(one, four);
  EXPECT_EQ(welded.num_points(), one.num_points());
  EXPECT_EQ(triangle_set(welded), triangle_set(one));
  return one;
}

}  // namespace keymesh::test
