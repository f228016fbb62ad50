#include "keymesh/generate/contour/marching_cubes_table.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace keymesh::generate {

namespace {

struct Vec3 {
  double x, y, z;
};

int coord(int corner, int axis) { return (corner >> axis) & 1; }

// Builds the table from the cube's geometry (no table data is typed in).
struct TableBuilder {
  MarchingCubesTable t{};
  std::vector<std::array<int, 4>> faces;  // corners in cyclic order around each face

  TableBuilder() {
    // The 12 edges: corner pairs that differ in exactly one coordinate.
    int e = 0;
    for (int a = 0; a < 8; ++a)
      for (int axis = 0; axis < 3; ++axis) {
        if (coord(a, axis) != 0) continue;
        const int b = a | (1 << axis);
        t.edges[e++] = CubeEdge{static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(b),
                                static_cast<std::uint8_t>(axis), static_cast<std::uint8_t>(coord(a, 0)),
                                static_cast<std::uint8_t>(coord(a, 1)), static_cast<std::uint8_t>(coord(a, 2))};
      }
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        std::array<int, 4> f{};
        const int cyc[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int k = 0; k < 4; ++k) f[k] = (side << axis) | (cyc[k][0] << u) | (cyc[k][1] << v);
        faces.push_back(f);
      }
  }

  int edge_of(int a, int b) const {
    for (int i = 0; i < 12; ++i)
      if ((t.edges[i].corner0 == a && t.edges[i].corner1 == b) || (t.edges[i].corner0 == b && t.edges[i].corner1 == a))
        return i;
    return -1;
  }

  Vec3 midpoint(int edge) const {
    const auto& ce = t.edges[edge];
    Vec3 p{double(coord(ce.corner0, 0)), double(coord(ce.corner0, 1)), double(coord(ce.corner0, 2))};
    (ce.axis == 0 ? p.x : ce.axis == 1 ? p.y : p.z) += 0.5;
    return p;
  }

  // Two cube edges on a common face. A diagonal between them inside a
  // polygon would lie on that face, where the neighbouring cube may draw the
  // same diagonal: the edge would then carry four triangles (non-manifold).
  bool share_face(int e1, int e2) const {
    for (int axis = 0; axis < 3; ++axis) {
      if (t.edges[e1].axis == axis || t.edges[e2].axis == axis) continue;
      const int c1 = coord(t.edges[e1].corner0, axis), c2 = coord(t.edges[e2].corner0, axis);
      if (c1 == c2) return true;
    }
    return false;
  }

  // Every triangulation of a polygon (cut edges in order) without such
  // diagonals, in a fixed order: the triangle on edge (p0, p1) takes each
  // apex whose two sides are polygon edges or allowed diagonals in turn, and
  // the two remaining pieces are triangulated the same way.
  void triangulations(const std::vector<int>& poly, std::vector<std::vector<std::array<int, 3>>>& out) const {
    const std::size_t m = poly.size();
    if (m < 3) {
      out.emplace_back();
      return;
    }
    if (m == 3) {
      out.push_back({{poly[0], poly[1], poly[2]}});
      return;
    }
    for (std::size_t k = 2; k < m; ++k) {
      const bool side1 = k == 2 || !share_face(poly[1], poly[k]);      // (p1, pk)
      const bool side2 = k == m - 1 || !share_face(poly[k], poly[0]);  // (pk, p0)
      if (!side1 || !side2) continue;
      const std::vector<int> a(poly.begin() + 1, poly.begin() + static_cast<std::ptrdiff_t>(k) + 1);
      std::vector<int> b(poly.begin() + static_cast<std::ptrdiff_t>(k), poly.end());
      b.push_back(poly[0]);
      std::vector<std::vector<std::array<int, 3>>> first, second;
      triangulations(a, first);
      triangulations(b, second);
      for (const auto& x : first)
        for (const auto& y : second) {
          std::vector<std::array<int, 3>> tris{{poly[0], poly[1], poly[k]}};
          tris.insert(tris.end(), x.begin(), x.end());
          tris.insert(tris.end(), y.begin(), y.end());
          out.push_back(std::move(tris));
        }
    }
  }

  // Total edge length of a triangulation with every point at its edge's
  // midpoint (each diagonal counted twice, the polygon's edges once: the
  // same for every triangulation of one polygon).
  double midpoint_length(const std::vector<std::array<int, 3>>& tris) const {
    double sum = 0;
    for (const auto& tr : tris)
      for (int k = 0; k < 3; ++k) {
        const Vec3 p = midpoint(tr[k]), q = midpoint(tr[(k + 1) % 3]);
        sum += std::sqrt((p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) + (p.z - q.z) * (p.z - q.z));
      }
    return sum;
  }

  // The triangulation with the shortest diagonals at the edge midpoints (the
  // first in the order above among equals). Taking the first allowed one
  // instead lets two triangles of some polygons cross: the 7-gons of a cube
  // with three corners outside, two of them diagonal on a face, where a
  // first-found split pairs long diagonals that pass each other for some
  // sample values (tests/generate/contour/marching_cubes_table_test.cpp sweeps every
  // case; vtkMarchingCubes' hand-made table has none either). The shortest
  // split keeps each triangle near the corner it cuts off.
  bool triangulate(const std::vector<int>& poly, std::vector<std::array<int, 3>>& out) const {
    std::vector<std::vector<std::array<int, 3>>> all;
    triangulations(poly, all);
    if (all.empty()) return false;
    std::size_t best = 0;
    double best_length = midpoint_length(all[0]);
    for (std::size_t i = 1; i < all.size(); ++i) {
      const double length = midpoint_length(all[i]);
      if (length < best_length - 1e-9) {
        best = i;
        best_length = length;
      }
    }
    out.insert(out.end(), all[best].begin(), all[best].end());
    return true;
  }

  // The contour segments on the cube's faces: each cut edge gets one
  // neighbour per face it lies on.
  std::array<std::vector<int>, 12> segments(int cube_case) const {
    auto inside = [&](int c) { return (cube_case >> c) & 1; };
    std::array<std::vector<int>, 12> adj;
    for (const auto& f : faces) {
      std::array<int, 4> fe{};
      for (int k = 0; k < 4; ++k) fe[k] = edge_of(f[k], f[(k + 1) % 4]);
      std::vector<int> cut;
      for (int k = 0; k < 4; ++k)
        if (inside(f[k]) != inside(f[(k + 1) % 4])) cut.push_back(k);
      std::vector<std::array<int, 2>> segs;
      if (cut.size() == 2) {
        segs.push_back({fe[cut[0]], fe[cut[1]]});
      } else if (cut.size() == 4) {
        // Ambiguous face: cut off every inside corner on its own.
        for (int k = 0; k < 4; ++k)
          if (inside(f[k])) segs.push_back({fe[(k + 3) % 4], fe[k]});
      }
      for (const auto& s : segs) {
        adj[s[0]].push_back(s[1]);
        adj[s[1]].push_back(s[0]);
      }
    }
    return adj;
  }

  // Orients a loop: its Newell normal must point from inside corners to
  // outside ones.
  void orient(std::vector<int>& loop, int cube_case) const {
    Vec3 n{0, 0, 0}, d{0, 0, 0};
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Vec3 p = midpoint(loop[i]), q = midpoint(loop[(i + 1) % loop.size()]);
      n.x += (p.y - q.y) * (p.z + q.z);
      n.y += (p.z - q.z) * (p.x + q.x);
      n.z += (p.x - q.x) * (p.y + q.y);
      const auto& ce = t.edges[loop[i]];
      const double sgn = (cube_case >> ce.corner0) & 1 ? 1.0 : -1.0;  // corner0 -> corner1 goes inside -> outside
      (ce.axis == 0 ? d.x : ce.axis == 1 ? d.y : d.z) += sgn;
    }
    if (n.x * d.x + n.y * d.y + n.z * d.z < 0) std::reverse(loop.begin(), loop.end());
  }

  // Every case: the segments' loops, oriented and triangulated.
  void add_case(int cube_case) {
    const std::array<std::vector<int>, 12> adj = segments(cube_case);
    std::array<bool, 12> seen{};
    int tri = 0;
    for (int start = 0; start < 12; ++start) {
      if (adj[start].empty() || seen[start]) continue;
      std::vector<int> loop;
      int prev = -1, cur = start;
      do {
        seen[cur] = true;
        loop.push_back(cur);
        const int next = (adj[cur][0] != prev) ? adj[cur][0] : adj[cur][1];
        prev = cur;
        cur = next;
      } while (cur != start);
      orient(loop, cube_case);
      std::vector<std::array<int, 3>> tris;
      if (!triangulate(loop, tris)) {
        // Not met by any of the 256 cases (the noise-volume test would see
        // non-manifold edges); a fan keeps the table whole regardless.
        tris.clear();
        for (std::size_t i = 1; i + 1 < loop.size(); ++i) tris.push_back({loop[0], loop[i], loop[i + 1]});
      }
      for (const auto& tr : tris) {
        for (int k = 0; k < 3; ++k) t.triangle_edges[cube_case][3 * tri + k] = static_cast<std::uint8_t>(tr[k]);
        ++tri;
      }
    }
    t.triangle_count[cube_case] = static_cast<std::uint8_t>(tri);
  }
};

MarchingCubesTable build_table() {
  TableBuilder b;
  for (int cube_case = 0; cube_case < 256; ++cube_case) b.add_case(cube_case);
  return b.t;
}

// x <-> z of a corner (c & 1 is x, c >> 2 is z).
int mirror_corner(int c) { return ((c & 1) << 2) | (c & 2) | ((c >> 2) & 1); }

MarchingCubesTable build_mirrored_table(const MarchingCubesTable& t) {
  MarchingCubesTable m = t;  // the same edges
  std::array<std::uint8_t, 12> mirror_edge{};
  for (int e = 0; e < 12; ++e) {
    const int a = mirror_corner(t.edges[e].corner0), b = mirror_corner(t.edges[e].corner1);
    for (int f = 0; f < 12; ++f)
      if ((t.edges[f].corner0 == a && t.edges[f].corner1 == b) || (t.edges[f].corner0 == b && t.edges[f].corner1 == a))
        mirror_edge[e] = static_cast<std::uint8_t>(f);
  }
  for (int cube_case = 0; cube_case < 256; ++cube_case) {
    int mirrored = 0;
    for (int c = 0; c < 8; ++c)
      if ((cube_case >> c) & 1) mirrored |= 1 << mirror_corner(c);
    m.triangle_count[cube_case] = t.triangle_count[mirrored];
    for (int tri = 0; tri < t.triangle_count[mirrored]; ++tri)
      for (int k = 0; k < 3; ++k)
        m.triangle_edges[cube_case][3 * tri + k] = mirror_edge[t.triangle_edges[mirrored][3 * tri + 2 - k]];
  }
  return m;
}

}  // namespace

const MarchingCubesTable& marching_cubes_table(bool reversed_axes) {
  static const MarchingCubesTable table = build_table();
  if (!reversed_axes) return table;
  static const MarchingCubesTable mirrored = build_mirrored_table(table);
  return mirrored;
}

}  // namespace keymesh::generate
