#include "keymesh/generate/marching_cubes_table.hpp"

#include <algorithm>
#include <vector>

namespace keymesh::generate {

namespace {

struct Vec3 {
  double x, y, z;
};

int coord(int corner, int axis) { return (corner >> axis) & 1; }

MarchingCubesTable build_table() {
  MarchingCubesTable t{};
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
  auto edge_of = [&](int a, int b) {
    for (int i = 0; i < 12; ++i)
      if ((t.edges[i].corner0 == a && t.edges[i].corner1 == b) || (t.edges[i].corner0 == b && t.edges[i].corner1 == a))
        return i;
    return -1;
  };
  // The 6 faces, corners listed in cyclic order around the face.
  std::vector<std::array<int, 4>> faces;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      std::array<int, 4> f{};
      const int cyc[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int k = 0; k < 4; ++k) f[k] = (side << axis) | (cyc[k][0] << u) | (cyc[k][1] << v);
      faces.push_back(f);
    }
  auto midpoint = [&](int edge) {
    const auto& ce = t.edges[edge];
    Vec3 p{double(coord(ce.corner0, 0)), double(coord(ce.corner0, 1)), double(coord(ce.corner0, 2))};
    (ce.axis == 0 ? p.x : ce.axis == 1 ? p.y : p.z) += 0.5;
    return p;
  };

  for (int cube_case = 0; cube_case < 256; ++cube_case) {
    auto inside = [&](int c) { return (cube_case >> c) & 1; };
    // Each cut edge gets one neighbour per face it lies on.
    std::array<std::vector<int>, 12> adj;
    for (const auto& f : faces) {
      std::array<int, 4> fe{};
      for (int k = 0; k < 4; ++k) fe[k] = edge_of(f[k], f[(k + 1) % 4]);
      std::vector<int> cut;
      for (int k = 0; k < 4; ++k)
        if (inside(f[k]) != inside(f[(k + 1) % 4])) cut.push_back(k);
      std::vector<std::array<int, 2>> segments;
      if (cut.size() == 2) {
        segments.push_back({fe[cut[0]], fe[cut[1]]});
      } else if (cut.size() == 4) {
        // Ambiguous face: cut off every inside corner on its own.
        for (int k = 0; k < 4; ++k)
          if (inside(f[k])) segments.push_back({fe[(k + 3) % 4], fe[k]});
      }
      for (const auto& s : segments) {
        adj[s[0]].push_back(s[1]);
        adj[s[1]].push_back(s[0]);
      }
    }
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
      // Orient: the Newell normal must point from inside corners to outside ones.
      Vec3 n{0, 0, 0}, d{0, 0, 0};
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const Vec3 p = midpoint(loop[i]), q = midpoint(loop[(i + 1) % loop.size()]);
        n.x += (p.y - q.y) * (p.z + q.z);
        n.y += (p.z - q.z) * (p.x + q.x);
        n.z += (p.x - q.x) * (p.y + q.y);
        const auto& ce = t.edges[loop[i]];
        const double sgn = inside(ce.corner0) ? 1.0 : -1.0;  // corner0 -> corner1 goes inside -> outside
        (ce.axis == 0 ? d.x : ce.axis == 1 ? d.y : d.z) += sgn;
      }
      if (n.x * d.x + n.y * d.y + n.z * d.z < 0) std::reverse(loop.begin(), loop.end());
      for (std::size_t i = 1; i + 1 < loop.size(); ++i) {
        t.triangle_edges[cube_case][3 * tri + 0] = static_cast<std::uint8_t>(loop[0]);
        t.triangle_edges[cube_case][3 * tri + 1] = static_cast<std::uint8_t>(loop[i]);
        t.triangle_edges[cube_case][3 * tri + 2] = static_cast<std::uint8_t>(loop[i + 1]);
        ++tri;
      }
    }
    t.triangle_count[cube_case] = static_cast<std::uint8_t>(tri);
  }
  return t;
}

}  // namespace

const MarchingCubesTable& marching_cubes_table() {
  static const MarchingCubesTable table = build_table();
  return table;
}

}  // namespace keymesh::generate
