// Face clusters of a multilod chunk piece one level coarser (see
// label_chunks.hpp): the points on exactly one plane of the chunk's box (a
// face) merge by the nearest grid point of spacing 2^lod on the face, where
// that keeps the face's cut simple. Decided from the face's cut alone (its
// points, keys and positions, and the piece's boundary edges lying in the
// face plane), which the two chunks sharing the face hold alike at every
// level: level 0 by construction, and each level's boundary is the image of
// the finer one's (a chain map), so both chunks make the same clusters and
// place them at the same bits. Points on a chunk edge line (two planes) are
// kept.
//
// A cluster is merged only if, at the positions the writer quantizes it to
// (the face's in-plane coordinates at the level's node: the same integers in
// both chunks, whose nodes share those coordinates' boxes), it is one run of
// one strand of the cut (its points joined by cut edges into a path, two cut
// edges leaving it), and the cut stays simple: no two image segments meet
// but at a shared end, no two meet folded back, no two image points within
// one quantization step, no two image points joined twice. Otherwise the
// cluster splits back into its finer points, and the face is checked again,
// until no merged cluster fails (a split cluster is never merged again, so
// this ends). So every merged point ends exactly two boundary edges in both
// chunks and is used there, and the coarse cut neither pinches nor folds.
// A merged cluster takes the key of its least point (unique in the piece,
// the same in both chunks).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <tuple>
#include <vector>

#include "first_seen_keys.hpp"
#include "label_chunks.hpp"

namespace keymesh::generate::detail {

namespace {

// One face's cut in the finer piece: its points (face points and the line
// points on its border lines; finer indices, increasing), which of them may
// merge, and its boundary edges (positions in `points`).
struct FaceCut {
  int axis = 0;
  std::vector<std::uint32_t> points;
  std::vector<char> movable;
  std::vector<std::array<std::uint32_t, 2>> edges;
};

// The piece's boundary edges (net directed count nonzero) between points on
// a common plane of its box, by face (2 * axis + upper), as finer indices.
std::array<std::vector<std::array<std::uint32_t, 2>>, 6> face_edges(const MultilodPiece& finer,
                                                                  const std::vector<OnBox>& box) {
  std::vector<std::tuple<std::uint32_t, std::uint32_t, int>> e;
  const std::uint32_t* triangles = finer.triangles.data();
  const std::size_t corners = finer.triangles.size();  // read once: the emplace_backs below may alias it
  for (std::size_t t = 0; t < corners; t += 3) {
    const std::uint32_t c[3] = {triangles[t], triangles[t + 1], triangles[t + 2]};
    const int axes[3] = {box[c[0]].axes, box[c[1]].axes, box[c[2]].axes};
    if (!((axes[0] & axes[1]) | (axes[1] & axes[2]) | (axes[2] & axes[0]))) continue;  // most: no edge on a plane
    for (int m = 0; m < 3; ++m) {
      const int n = m == 2 ? 0 : m + 1;
      const std::uint32_t u = c[m], v = c[n];
      if (axes[m] & axes[n]) e.emplace_back(std::min(u, v), std::max(u, v), u < v ? 1 : -1);
    }
  }
  std::sort(e.begin(), e.end());
  std::array<std::vector<std::array<std::uint32_t, 2>>, 6> out;
  for (std::size_t b = 0, x = 0; b < e.size(); b = x) {
    const auto [u, v, s0] = e[b];
    int net = 0;
    for (x = b; x < e.size() && std::get<0>(e[x]) == u && std::get<1>(e[x]) == v; ++x) net += std::get<2>(e[x]);
    if (net == 0) continue;
    for (int a = 0; a < 3; ++a) {
      const int both = box[u].axes & box[v].axes;
      const int up = box[u].upper >> a & 1;
      if ((both >> a & 1) && up == (box[v].upper >> a & 1)) out[static_cast<std::size_t>(2 * a + up)].push_back({u, v});
    }
  }
  return out;
}

// The cuts of the six faces (2 * axis + upper), their points in increasing
// index. `at`: scratch, one per point.
std::array<FaceCut, 6> face_cuts(const std::vector<OnBox>& box,
                                 const std::array<std::vector<std::array<std::uint32_t, 2>>, 6>& edges,
                                 std::vector<std::uint32_t>& at) {
  std::array<FaceCut, 6> cuts;
  for (std::uint32_t i = 0; i < box.size(); ++i) {
    if (!box[i].axes) continue;
    const char movable = box[i].count() == 1 ? 1 : 0;
    for (int a = 0; a < 3; ++a) {
      if (!(box[i].axes >> a & 1)) continue;
      FaceCut& cut = cuts[static_cast<std::size_t>(2 * a + (box[i].upper >> a & 1))];
      cut.points.push_back(i);
      cut.movable.push_back(movable);
    }
  }
  for (int f = 0; f < 6; ++f) {
    FaceCut& cut = cuts[static_cast<std::size_t>(f)];
    cut.axis = f / 2;
    for (std::uint32_t k = 0; k < cut.points.size(); ++k) at[cut.points[k]] = k;
    cut.edges.reserve(edges[static_cast<std::size_t>(f)].size());
    for (const auto& [u, v] : edges[static_cast<std::size_t>(f)]) cut.edges.push_back({at[u], at[v]});
  }
  return cuts;
}

// A clustering of a face's cut: per cut point its cluster's first point
// (increasing index: the least key), and per cluster (at that point) its
// size and its image position, in-plane coordinates quantized as the writer
// quantizes them at the level.
struct Clusters {
  std::vector<std::uint32_t> root, size;
  std::vector<std::array<std::int64_t, 2>> at;
};

Clusters cluster(const FaceCut& cut, const std::vector<std::uint64_t>& grid_key, const MultilodPiece& finer,
                 const MultilodGrid& grid) {
  const std::size_t n = cut.points.size();
  Clusters c;
  c.root.resize(n), c.size.assign(n, 0), c.at.resize(n);
  const FirstSeenKeys f = first_seen_keys(grid_key.data(), static_cast<Id>(n));  // a key's first point: its least
  for (std::size_t k = 0; k < n; ++k) c.root[k] = f.first[f.of_point[k]];
  const int lod = static_cast<int>(finer.lod + 1);
  const double top = std::ldexp(1.0, grid.vertex_quantization_bits) - 1;
  const auto top_step = static_cast<std::int64_t>(top);
  std::vector<double> sum(n);
  for (int j = 1; j < 3; ++j) {
    const int a = (cut.axis + j) % 3;
    std::fill(sum.begin(), sum.end(), 0.0);
    for (std::size_t k = 0; k < n; ++k) {  // increasing index, as the KEY-REDUCE sums
      sum[c.root[k]] += finer.points[3 * static_cast<std::size_t>(cut.points[k]) + static_cast<std::size_t>(a)];
      c.size[c.root[k]] += j == 1 ? 1 : 0;
    }
    const double size = std::ldexp(static_cast<double>(grid.chunk_shape[a]), lod);
    const double origin = grid.grid_origin[a] + static_cast<double>(finer.chunk[a] >> lod) * size;
    const double margin = grid.margin(a, lod);
    for (std::size_t r = 0; r < n; ++r) {
      if (c.root[r] != r) continue;
      const float mean = static_cast<float>(sum[r] / static_cast<double>(c.size[r]));
      const double v = off_chunk_planes(grid, a, mean, margin);
      const std::int64_t q = round_half_away((v - origin) / size * top);
      c.at[r][static_cast<std::size_t>(j - 1)] = std::clamp<std::int64_t>(q, 0, top_step);
    }
  }
  return c;
}

// Merged clusters (two or more points) that are not one run of one strand:
// their points joined by their inner cut edges into one path with two cut
// edges leaving it; and both ends of image edges joined twice.
void flag_broken_runs(const FaceCut& cut, const Clusters& c, std::vector<char>& bad) {
  const std::size_t n = cut.points.size();
  std::vector<std::uint32_t> inside(n, 0), out(n, 0), link(n);
  std::iota(link.begin(), link.end(), 0u);
  auto find = [&](std::uint32_t i) { while (link[i] != i) i = link[i] = link[link[i]]; return i; };
  std::vector<std::array<std::uint32_t, 2>> image;
  for (const auto& [u, v] : cut.edges) {
    const std::uint32_t ru = c.root[u], rv = c.root[v];
    if (ru == rv) {
      ++inside[ru];
      const std::uint32_t fu = find(u), fv = find(v);
      link[std::max(fu, fv)] = std::min(fu, fv);
    } else {
      ++out[ru], ++out[rv];
      image.push_back({std::min(ru, rv), std::max(ru, rv)});
    }
  }
  std::vector<std::uint32_t> parts(n, 0);
  for (std::uint32_t k = 0; k < n; ++k) parts[c.root[k]] += find(k) == k ? 1 : 0;
  for (std::uint32_t r = 0; r < n; ++r)
    if (c.root[r] == r && c.size[r] > 1 && (parts[r] != 1 || out[r] != 2 || inside[r] + 1 != c.size[r])) bad[r] = 1;
  std::sort(image.begin(), image.end());
  for (std::size_t k = 1; k < image.size(); ++k)
    if (image[k] == image[k - 1]) bad[image[k][0]] = bad[image[k][1]] = 1;
}

using Point2 = std::array<std::int64_t, 2>;

std::int64_t orient(const Point2& a, const Point2& b, const Point2& c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}
int sign(std::int64_t v) { return (v > 0) - (v < 0); }
bool on_segment(const Point2& a, const Point2& b, const Point2& p) {  // p collinear with a, b
  return std::min(a[0], b[0]) <= p[0] && p[0] <= std::max(a[0], b[0]) && std::min(a[1], b[1]) <= p[1] &&
         p[1] <= std::max(a[1], b[1]);
}
// Closed segments ab and cd meet (touching counts).
bool meet(const Point2& a, const Point2& b, const Point2& c, const Point2& d) {
  const int o1 = sign(orient(a, b, c)), o2 = sign(orient(a, b, d)), o3 = sign(orient(c, d, a)), o4 = sign(orient(c, d, b));
  if (o1 != o2 && o3 != o4) return true;
  return (o1 == 0 && on_segment(a, b, c)) || (o2 == 0 && on_segment(a, b, d)) || (o3 == 0 && on_segment(c, d, a)) ||
         (o4 == 0 && on_segment(c, d, b));
}

// Two image segments: bad if they share no end and meet, or share one end
// and overlap along a line (the cut folded back on itself).
bool segments_clash(const Point2& a, const Point2& b, std::uint32_t ra, std::uint32_t rb, const Point2& c,
                    const Point2& d, std::uint32_t rc, std::uint32_t rd) {
  if (ra == rc || ra == rd || rb == rc || rb == rd) {
    const std::uint32_t s = (ra == rc || ra == rd) ? ra : rb;
    const Point2& v = s == ra ? a : b;
    const Point2& x = s == ra ? b : a;
    const Point2& y = (s == rc) ? d : c;
    return orient(v, x, y) == 0 && (x[0] - v[0]) * (y[0] - v[0]) + (x[1] - v[1]) * (y[1] - v[1]) > 0;
  }
  return meet(a, b, c, d);
}

// Both ends of image segments that clash, or are a point; merged clusters
// closer than two steps to another image point (Chebyshev <= 1, which the
// writer's join would make one).
void flag_clashes(const FaceCut& cut, const Clusters& c, std::vector<char>& bad) {
  struct Seg {
    std::uint32_t r[2];
    std::int64_t lo, hi;  // along the first in-plane axis
  };
  std::vector<Seg> segs;
  for (const auto& [u, v] : cut.edges) {
    const std::uint32_t ru = c.root[u], rv = c.root[v];
    if (ru == rv) continue;
    if (c.at[ru] == c.at[rv]) bad[ru] = bad[rv] = 1;
    segs.push_back({{ru, rv}, std::min(c.at[ru][0], c.at[rv][0]), std::max(c.at[ru][0], c.at[rv][0])});
  }
  std::sort(segs.begin(), segs.end(), [](const Seg& x, const Seg& y) { return x.lo < y.lo; });
  for (std::size_t i = 0; i < segs.size(); ++i)
    for (std::size_t j = i + 1; j < segs.size() && segs[j].lo <= segs[i].hi; ++j) {
      const Seg &s = segs[i], &t = segs[j];
      if ((s.r[0] == t.r[0] && s.r[1] == t.r[1]) || (s.r[0] == t.r[1] && s.r[1] == t.r[0])) continue;  // flagged as joined twice
      if (segments_clash(c.at[s.r[0]], c.at[s.r[1]], s.r[0], s.r[1], c.at[t.r[0]], c.at[t.r[1]], t.r[0], t.r[1]))
        bad[s.r[0]] = bad[s.r[1]] = bad[t.r[0]] = bad[t.r[1]] = 1;
    }
  std::vector<std::uint32_t> roots;
  for (std::uint32_t r = 0; r < c.root.size(); ++r)
    if (c.root[r] == r) roots.push_back(r);
  std::sort(roots.begin(), roots.end(), [&](std::uint32_t x, std::uint32_t y) { return c.at[x] < c.at[y]; });
  for (std::size_t i = 0; i < roots.size(); ++i)
    for (std::size_t j = i + 1; j < roots.size() && c.at[roots[j]][0] <= c.at[roots[i]][0] + 1; ++j)
      if (std::abs(c.at[roots[j]][1] - c.at[roots[i]][1]) <= 1 && (c.size[roots[i]] > 1 || c.size[roots[j]] > 1))
        bad[roots[i]] = bad[roots[j]] = 1;
}

// A face's in-plane frame at the level's spacing: its two in-plane axes and
// the chunk's planes along them, computed once per face.
class FaceFrame {
 public:
  FaceFrame(const MultilodGrid& grid, const std::array<std::uint32_t, 3>& chunk, int axis, double step) : step_(step) {
    for (int j = 0; j < 2; ++j) {
      axes_[j] = (axis + j + 1) % 3;
      lo_[j] = grid.plane(axes_[j], chunk[static_cast<std::size_t>(axes_[j])]);
      hi_[j] = grid.plane(axes_[j], chunk[static_cast<std::size_t>(axes_[j])] + 1);
    }
  }
  // The grid key of a movable cut point: its in-plane grid point (relative
  // to the chunk's corner, which both chunks of the face share along those
  // axes).
  std::uint64_t grid_key(const float* p) const {
    std::uint64_t key = 0;
    for (int j = 0; j < 2; ++j) {
      const std::int64_t local = round_half_away((static_cast<double>(p[axes_[j]]) - lo_[j]) / step_);
      key = key << 32 | static_cast<std::uint32_t>(local);
    }
    return key;
  }
  // Within half a grid step of the face's border (a chunk edge line): such a
  // point stays fine, as the line points do. The triangles there join this
  // face's cut to the neighbouring face's, each coarsened by its own face's
  // rule; merged near the line they folded over each other (measured), and
  // no split of an inner point mends that.
  bool near_border(const float* p) const {
    for (int j = 0; j < 2; ++j) {
      const double v = p[axes_[j]];
      if (v - lo_[j] < step_ / 2 || hi_[j] - v < step_ / 2) return true;
    }
    return false;
  }

 private:
  double step_;
  int axes_[2];
  double lo_[2], hi_[2];
};

// Clusters of one face, merged where the checks allow; writes the merged
// points' coarse keys (their cluster's least key) into `keys`.
void cluster_face(const FaceCut& cut, const MultilodPiece& finer, const MultilodGrid& grid,
                  std::vector<std::uint64_t>& keys) {
  const std::size_t n = cut.points.size();
  const double step = std::ldexp(1.0, static_cast<int>(finer.lod + 1));
  std::vector<std::uint64_t> grid_key(n);
  constexpr std::uint64_t kFine = std::uint64_t{1} << 63;  // then the point's index: a cluster of its own
  const FaceFrame frame(grid, finer.chunk, cut.axis, step);
  for (std::size_t k = 0; k < n; ++k) {
    const float* p = finer.points.data() + 3 * static_cast<std::size_t>(cut.points[k]);
    grid_key[k] = cut.movable[k] && !frame.near_border(p) ? frame.grid_key(p) : kFine | k;
  }
  for (;;) {
    const Clusters c = cluster(cut, grid_key, finer, grid);
    std::vector<char> bad(n, 0);
    flag_broken_runs(cut, c, bad);
    flag_clashes(cut, c, bad);
    bool split = false;
    for (std::size_t k = 0; k < n; ++k)
      if (bad[c.root[k]] && c.size[c.root[k]] > 1) grid_key[k] = kFine | k, split = true;
    if (split) continue;
    for (std::size_t k = 0; k < n; ++k) keys[cut.points[k]] = finer.point_keys[cut.points[c.root[k]]];
    return;
  }
}

}  // namespace

void cluster_face_points(const MultilodPiece& finer, const MultilodGrid& grid, std::vector<std::uint64_t>& keys) {
  const ChunkBox chunk_box(grid, finer.chunk);
  std::vector<OnBox> box(finer.point_keys.size());
  for (std::size_t i = 0; i < box.size(); ++i) box[i] = chunk_box.at(finer.points.data() + 3 * i);
  std::vector<std::uint32_t> at(box.size());
  for (const FaceCut& cut : face_cuts(box, face_edges(finer, box), at))
    if (!cut.points.empty()) cluster_face(cut, finer, grid, keys);
}

}  // namespace keymesh::generate::detail
