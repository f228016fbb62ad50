// Multilod levels coarsen the chunk faces too (docs/decisions/labels-lod-fold-guard.md,
// "Face clusters"): fewer points on the chunk faces at each coarser level,
// while neighbouring chunks still hold the same points on their common face
// and no level's triangles cross at the positions the writer quantizes them
// to. Before the face clusters, face points were never coarsened (the counts
// below were equal at every level).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <set>
#include <tuple>

#include "keymesh/analyze/self_intersections.hpp"
#include "keymesh/generate/labels/labels_multilod.hpp"
#include "label_map.hpp"

using namespace keymesh;
using generate::MultilodGrid;
using generate::MultilodPiece;

namespace {

// Three balls of labels 1-3, two of them touching, across many chunk faces.
ImageGrid balls() {
  return test::label_map({44, 40, 36}, [](Id i, Id j, Id k) {
    auto in = [&](double cx, double cy, double cz, double r) {
      return (i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz) <= r * r;
    };
    if (in(15, 16, 17, 12)) return 1;
    if (in(30, 22, 18, 11)) return 2;
    if (in(22, 30, 20, 8)) return 3;
    return 0;
  });
}

// The plane a point lies on when exactly one coordinate is on a chunk plane
// (a face point; -1 otherwise).
int face_axis(const float* p, const MultilodGrid& grid) {
  int axis = -1, count = 0;
  for (int a = 0; a < 3; ++a) {
    const double c = (p[a] - grid.grid_origin[a]) / static_cast<double>(grid.chunk_shape[a]);
    if (c == std::floor(c)) axis = a, ++count;
  }
  return count == 1 ? axis : -1;
}

using FacePoint = std::tuple<std::uint64_t, std::uint64_t, int, std::uint32_t, std::uint32_t, std::uint32_t>;

// Every face point of every piece of `lod`: (segment, key, axis, position bits).
std::multiset<FacePoint> face_points(const std::vector<MultilodPiece>& pieces, const MultilodGrid& grid, std::uint32_t lod) {
  std::multiset<FacePoint> out;
  for (const MultilodPiece& p : pieces) {
    if (p.lod != lod) continue;
    for (std::size_t i = 0; i < p.point_keys.size(); ++i) {
      const float* q = &p.points[3 * i];
      const int axis = face_axis(q, grid);
      if (axis < 0) continue;
      std::uint32_t b[3];
      std::memcpy(b, q, sizeof b);
      out.emplace(p.segment, p.point_keys[i], axis, b[0], b[1], b[2]);
    }
  }
  return out;
}

// Crossing pairs of one segment's pieces of `lod`, each point at the
// integers the writer quantizes it to over its node (node * (2^bits - 1) +
// value, so the pieces join where their points coincide).
Id crossing_pairs(const std::vector<MultilodPiece>& pieces, const MultilodGrid& grid, std::uint64_t segment,
                  std::uint32_t lod) {
  const double top = std::ldexp(1.0, grid.vertex_quantization_bits) - 1;
  std::map<std::array<double, 3>, PointIndex> index;
  SurfaceMesh mesh;
  std::vector<float> points;
  std::vector<PointIndex> triangles;
  for (const MultilodPiece& p : pieces) {
    if (p.lod != lod || p.segment != segment) continue;
    std::vector<PointIndex> at(p.point_keys.size());
    for (std::size_t i = 0; i < at.size(); ++i) {
      std::array<double, 3> q{};
      for (int a = 0; a < 3; ++a) {
        const double size = std::ldexp(static_cast<double>(grid.chunk_shape[a]), static_cast<int>(lod));
        const double node = static_cast<double>(p.chunk[a] >> lod);
        const double origin = grid.grid_origin[a] + node * size;
        q[a] = node * top + std::clamp(std::round((p.points[3 * i + a] - origin) / size * top), 0.0, top);
      }
      const auto [it, added] = index.emplace(q, static_cast<PointIndex>(index.size()));
      if (added) points.insert(points.end(), q.begin(), q.end());
      at[i] = it->second;
    }
    for (std::uint32_t c : p.triangles) triangles.push_back(at[c]);
  }
  mesh.points.assign(points.begin(), points.end());
  mesh.connectivity.assign(triangles.begin(), triangles.end());
  return analyze::find_self_intersections(mesh).self_intersections;
}

}  // namespace

TEST(LabelsMultilodFaces, FacePointsCoarsenAndStillAgree) {
  generate::MultilodOptions o;
  o.chunk_shape = {16, 16, 16};
  o.lods = 3;
  const ImageGrid g = balls();
  const auto pieces = generate::multilod_pieces(g, o);
  const MultilodGrid grid = generate::multilod_grid(g.dims, o);
  std::size_t count[3];
  for (std::uint32_t lod = 0; lod < 3; ++lod) {
    const auto points = face_points(pieces, grid, lod);
    // Each face point is held by the two chunks of its face, with the same
    // key and bits (a point on one face lies in no third chunk).
    for (auto it = points.begin(); it != points.end(); it = points.upper_bound(*it))
      EXPECT_EQ(points.count(*it), 2u) << "lod " << lod << " segment " << std::get<0>(*it) << " key " << std::get<1>(*it);
    count[lod] = points.size() / 2;
    for (std::uint64_t segment = 1; segment <= 3; ++segment)
      EXPECT_EQ(crossing_pairs(pieces, grid, segment, lod), 0) << "segment " << segment << " lod " << lod;
  }
  EXPECT_GT(count[0], 500u);  // the surfaces cross many chunk faces
  // Spacing 2 and 4 on the faces, half a step from the faces' borders kept:
  // before face clusters every level kept all of them.
  std::printf("face points per level: %zu %zu %zu\n", count[0], count[1], count[2]);
  EXPECT_LT(count[1], count[0] * 7 / 10);
  EXPECT_LT(count[2], count[1] * 9 / 10);
}
