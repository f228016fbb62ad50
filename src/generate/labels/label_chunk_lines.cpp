// A coarse chunk piece's boundary led past the points on the chunk's edge
// lines that it does not cross (see label_chunks.hpp). Why: a point K on an
// edge line is shared by four chunks, each of which sees two of the four
// faces around the line. On each face the boundary is the image of level 0's
// cut curve (the same in both chunks of the face), and its net count at K,
// edges out minus edges in, is the number of surface crossings of the line
// merged into K (with a sign per face): the same on all four faces. Where
// that count is not zero, every face's boundary holds K, so all four chunks
// keep it. Where it is zero, one face's strands at K may cancel while
// another's do not, so one chunk would keep K and the next leave it; leading
// every face's strands past K (pairs closed by a triangle through K) leaves
// K on no face's boundary, so no chunk keeps it on the line.
#include <algorithm>
#include <map>
#include <tuple>
#include <vector>

#include "label_chunks.hpp"

namespace keymesh::generate::detail {

namespace {

// Net directed boundary edges between box points: out[u][v] = -out[v][u],
// the times u -> v appears minus v -> u.
using NetEdges = std::map<std::uint32_t, std::map<std::uint32_t, int>>;

void add_edge(NetEdges& net, std::uint32_t u, std::uint32_t v, int count) {
  net[u][v] += count;
  net[v][u] -= count;
}

NetEdges boundary_between_box_points(const MultilodPiece& piece, const std::vector<OnBox>& box) {
  NetEdges net;
  for (std::size_t t = 0; t < piece.triangles.size(); t += 3)
    for (int m = 0; m < 3; ++m) {
      const std::uint32_t a = piece.triangles[t + m], b = piece.triangles[t + (m + 1) % 3];
      if (box[a].axes != 0 && box[b].axes != 0) add_edge(net, a, b, 1);
    }
  return net;
}

// The face of the line point `k` (one of its two planes: `axis`) that the
// edge to box point x lies on, or -1 when x lies on both (then the edge
// runs along the line) or on neither.
int face_of_edge(const OnBox& k, const OnBox& x) {
  int face = -1, faces = 0;
  for (int a = 0; a < 3; ++a)
    if ((k.axes >> a & 1) && (x.axes >> a & 1) && (k.upper >> a & 1) == (x.upper >> a & 1)) face = a, ++faces;
  return faces == 1 ? face : -1;
}

// The triangles that lead the boundary past line point k, if it balances on
// both its faces; none otherwise (k a crossing, or an edge along its line).
std::vector<std::uint32_t> reroute_at(NetEdges& net, const std::vector<OnBox>& box, std::uint32_t k) {
  std::vector<std::uint32_t> in[3], out[3];  // per face axis, other ends in key (index) order
  for (const auto& [x, count] : net[k]) {
    if (count == 0) continue;
    const int face = face_of_edge(box[k], box[x]);
    if (face < 0) return {};
    for (int c = 0; c < std::abs(count); ++c) (count > 0 ? out : in)[face].push_back(x);
  }
  for (int a = 0; a < 3; ++a)
    if (in[a].size() != out[a].size()) return {};
  std::vector<std::uint32_t> added;
  for (int a = 0; a < 3; ++a)
    for (std::size_t j = 0; j < in[a].size(); ++j) {
      const std::uint32_t x = in[a][j], y = out[a][j];
      added.insert(added.end(), {y, k, x});  // boundary x -> k -> y becomes x -> y
      add_edge(net, y, k, 1);
      add_edge(net, k, x, 1);
      add_edge(net, x, y, 1);
    }
  return added;
}

// Triangles on the same three points with opposite orientations cancel in
// pairs (as coarsening's do), so an added triangle that closes an existing
// one leaves neither.
void cancel_opposite_triangles(std::vector<std::uint32_t>& triangles) {
  std::map<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>, std::vector<std::size_t>> by_points[2];
  const std::size_t n = triangles.size() / 3;
  for (std::size_t t = 0; t < n; ++t) {
    const std::uint32_t* v = triangles.data() + 3 * t;
    const int r = v[0] < v[1] ? (v[0] < v[2] ? 0 : 2) : (v[1] < v[2] ? 1 : 2);
    const std::uint32_t a = v[r], b = v[(r + 1) % 3], c = v[(r + 2) % 3];
    by_points[b < c ? 0 : 1][{a, std::min(b, c), std::max(b, c)}].push_back(t);
  }
  std::vector<char> drop(n, 0);
  for (const auto& [points, up] : by_points[0]) {
    const auto down = by_points[1].find(points);
    if (down == by_points[1].end()) continue;
    const std::size_t pairs = std::min(up.size(), down->second.size());
    for (std::size_t j = 0; j < pairs; ++j) drop[up[j]] = drop[down->second[j]] = 1;
  }
  std::size_t kept = 0;
  for (std::size_t t = 0; t < n; ++t)
    if (!drop[t]) std::copy_n(triangles.begin() + 3 * t, 3, triangles.begin() + 3 * kept++);
  triangles.resize(3 * kept);
}

// Points no triangle uses any more (their triangles cancelled) left out,
// the others renumbered in the same (key) order.
void drop_unused_points(MultilodPiece& piece) {
  const std::size_t n = piece.point_keys.size();
  std::vector<std::uint32_t> rank(n, 0);
  for (std::uint32_t c : piece.triangles) rank[c] = 1;
  std::uint32_t kept = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!rank[i]) continue;
    piece.point_keys[kept] = piece.point_keys[i];
    std::copy_n(piece.points.begin() + 3 * i, 3, piece.points.begin() + 3 * kept);
    rank[i] = kept++;
  }
  piece.point_keys.resize(kept);
  piece.points.resize(3 * static_cast<std::size_t>(kept));
  for (std::uint32_t& c : piece.triangles) c = rank[c];
}

}  // namespace

std::vector<char> held_by_boundary(const MultilodPiece& piece, const std::vector<OnBox>& box) {
  std::vector<char> held(box.size(), 0);
  for (const auto& [u, edges] : boundary_between_box_points(piece, box))
    for (const auto& [v, count] : edges) held[u] = held[u] || count != 0;
  return held;
}

void reroute_line_boundaries(MultilodPiece& piece, const MultilodGrid& grid) {
  const std::size_t n = piece.point_keys.size();
  std::vector<OnBox> box(n);
  for (std::size_t i = 0; i < n; ++i) box[i] = on_box(piece.points.data() + 3 * i, grid, piece.chunk);
  NetEdges net = boundary_between_box_points(piece, box);
  bool added = false;
  // In key order: a face's line points are then led in the same order in
  // both its chunks (leading one changes only its own faces' boundaries).
  for (std::uint32_t k = 0; k < n; ++k) {
    if (box[k].count() != 2 || !net.count(k)) continue;
    const std::vector<std::uint32_t> closing = reroute_at(net, box, k);
    piece.triangles.insert(piece.triangles.end(), closing.begin(), closing.end());
    added = added || !closing.empty();
  }
  if (!added) return;
  cancel_opposite_triangles(piece.triangles);
  drop_unused_points(piece);
}

}  // namespace keymesh::generate::detail
