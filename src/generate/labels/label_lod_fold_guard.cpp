// The coarsening's fold guard for multilod chunk pieces (see label_chunks.hpp):
// the inner clusters (coarse points of class 0) at a corner of a coarse
// triangle that crosses another of the piece, or is a line, are split back
// into their finer points, each with a key of its own, until no such
// cluster is left; then the inner corners of triangles still crossing are
// lifted off the chunk planes (points_to_lift), until none is left to lift.
// Only inner points are split or moved: a chunk decides them from its own
// triangles, which no neighbour sees, and its points on the box are
// coarsened from their face's cut alone (label_face_clusters.cpp), so
// neighbouring chunks still agree on their common face.
// Why within the piece is enough: the pieces of two chunks meet only on
// their common face, where both hold the same boundary edges, and inner
// points keep a margin from every chunk plane. Judged at the positions the
// writer quantizes the points to (so what a viewer draws), exactly
// (analyze/self_intersections.hpp). Points that quantize to one position are
// merged by the writer (io/neuroglancer/coincident_points.hpp), so a
// triangle collapsed that way is left to it.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "keymesh/analyze/self_intersections.hpp"
#include "label_chunks.hpp"

namespace keymesh::generate::detail {

namespace {

constexpr int kClassShift = 61;
constexpr int kSplitBit = 60;        // an inner point split out of its cluster
constexpr int kRankShift = 54;       // then its rank in the cluster (6 bits)
constexpr std::uint64_t kMaxRank = 63;
constexpr int kFieldBits = 19;       // a coarse key's grid fields (label_chunk_lods.cpp),
constexpr int kSplitFieldBits = 18;  // kept in 18 bits each
constexpr double kLiftDivisor = 8;   // a lifted point keeps 2^lod / 8 samples from the chunk planes

bool splittable(std::uint64_t key) { return key >> kClassShift == 0 && !(key >> kSplitBit & 1); }

// The piece's points as the writer quantizes them over the piece's node
// (io/neuroglancer/node_fragment.hpp): integers, exact in float.
Array<float> quantized_points(const MultilodPiece& piece, const MultilodGrid& grid) {
  const double top = std::ldexp(1.0, grid.vertex_quantization_bits) - 1;
  Array<float> out(piece.points.size());
  for (int a = 0; a < 3; ++a) {
    const double size = std::ldexp(static_cast<double>(grid.chunk_shape[a]), static_cast<int>(piece.lod));
    const double origin = grid.grid_origin[a] + static_cast<double>(piece.chunk[a] >> piece.lod) * size;
    for (std::size_t i = static_cast<std::size_t>(a); i < out.size(); i += 3)
      out[i] = static_cast<float>(std::clamp(std::round((piece.points[i] - origin) / size * top), 0.0, top));
  }
  return out;
}

bool same_point(const float* a, const float* b) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; }

// analyze::triangle_has_area for quantized corners: integers below
// 2^kExactAreaBits, so the edges' cross product is exact in 64-bit integers
// and is zero exactly when the triangle has no area (no exact fallback to
// pay for, as orient2d has for collinear corners).
constexpr int kExactAreaBits = 30;
bool quantized_has_area(const float* a, const float* b, const float* c) {
  std::int64_t u[3], v[3];
  for (int k = 0; k < 3; ++k) {
    u[k] = static_cast<std::int64_t>(b[k]) - static_cast<std::int64_t>(a[k]);
    v[k] = static_cast<std::int64_t>(c[k]) - static_cast<std::int64_t>(a[k]);
  }
  return u[1] * v[2] != u[2] * v[1] || u[2] * v[0] != u[0] * v[2] || u[0] * v[1] != u[1] * v[0];
}

}  // namespace

std::vector<char> crossing_triangles(const MultilodPiece& piece, const MultilodGrid& grid) {
  const std::size_t n = piece.triangles.size() / 3;
  std::vector<char> bad(n, 0);
  SurfaceMesh mesh;
  mesh.points = quantized_points(piece, grid);
  mesh.connectivity.assign(piece.triangles.begin(), piece.triangles.end());
  const analyze::SelfIntersectionReport r =
      analyze::find_self_intersections(mesh, std::numeric_limits<std::size_t>::max());
  for (const auto& pair : r.pairs) bad[static_cast<std::size_t>(pair[0])] = bad[static_cast<std::size_t>(pair[1])] = 1;
  if (r.zero_area_triangles == 0) return bad;
  const bool exact = grid.vertex_quantization_bits <= kExactAreaBits;
  for (std::size_t t = 0; t < n; ++t) {
    const std::uint32_t* v = piece.triangles.data() + 3 * t;
    const float *a = &mesh.points[3 * v[0]], *b = &mesh.points[3 * v[1]], *c = &mesh.points[3 * v[2]];
    // Cheap position compares first: most triangles without area are collapsed ones.
    if (same_point(a, b) || same_point(b, c) || same_point(a, c)) continue;
    if (!(exact ? quantized_has_area(a, b, c) : analyze::triangle_has_area({a, b, c}))) bad[t] = 1;
  }
  return bad;
}

std::vector<std::uint64_t> points_to_lift(const MultilodPiece& coarse, const MultilodGrid& grid,
                                          const std::vector<char>& bad) {
  std::vector<std::uint64_t> out;
  for (std::size_t t = 0; t < bad.size(); ++t)
    for (int m = 0; bad[t] && m < 3; ++m) {
      const std::uint32_t v = coarse.triangles[3 * t + m];
      if (!on_box(coarse.points.data() + 3 * v, grid, coarse.chunk).axes) out.push_back(coarse.point_keys[v]);
    }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void lift_off_planes(MultilodPiece& coarse, const MultilodGrid& grid, const std::vector<std::uint64_t>& lifted) {
  const double lift = std::ldexp(1.0, static_cast<int>(coarse.lod)) / kLiftDivisor;
  for (std::size_t i = 0; i < coarse.point_keys.size(); ++i) {
    if (!std::binary_search(lifted.begin(), lifted.end(), coarse.point_keys[i])) continue;
    float* p = coarse.points.data() + 3 * i;
    for (int a = 0; a < 3; ++a) {
      const double lo = grid.plane(a, coarse.chunk[a]), hi = grid.plane(a, coarse.chunk[a] + 1);
      const double d = std::min(lift, static_cast<double>(grid.chunk_shape[a]) / 4);
      if (p[a] - lo < d) p[a] = static_cast<float>(lo + d);
      else if (hi - p[a] < d) p[a] = static_cast<float>(hi - d);
    }
  }
}

std::vector<std::uint64_t> clusters_to_split(const MultilodPiece& coarse, const std::vector<char>& bad) {
  std::vector<std::uint64_t> out;
  for (std::size_t t = 0; t < bad.size(); ++t) {
    if (!bad[t]) continue;
    for (int m = 0; m < 3; ++m) {
      const std::uint64_t key = coarse.point_keys[coarse.triangles[3 * t + m]];
      if (splittable(key)) out.push_back(key);
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

bool split_clusters(std::vector<std::uint64_t>& coarse_keys, const std::vector<std::uint64_t>& clusters) {
  // Finer points in index (key) order: a point's rank in its cluster is the
  // number of its cluster's points before it.
  std::vector<std::uint64_t> seen(clusters.size(), 0);
  bool split = false;
  for (std::uint64_t& key : coarse_keys) {
    const auto at = std::lower_bound(clusters.begin(), clusters.end(), key);
    if (at == clusters.end() || *at != key) continue;
    std::uint64_t fields = 0;
    bool fit = true;
    for (int a = 0; a < 3; ++a) {
      const std::uint64_t f = key >> (kFieldBits * a) & ((std::uint64_t{1} << kFieldBits) - 1);
      fit = fit && !(f >> kSplitFieldBits);
      fields |= f << (kSplitFieldBits * a);
    }
    if (!fit) continue;
    const std::uint64_t rank = std::min(seen[static_cast<std::size_t>(at - clusters.begin())]++, kMaxRank);
    key = fields | std::uint64_t{1} << kSplitBit | rank << kRankShift;
    split = true;
  }
  return split;
}

}  // namespace keymesh::generate::detail
