#include "coarse_cases.hpp"

#include <stdexcept>

#include "coarse_folds.hpp"
#include "keymesh/generate/marching_cubes_table.hpp"

namespace keymesh::generate {

namespace {

CoarseVoxelTable build() {
  const auto& mc = marching_cubes_table();
  for (int e = 0; e < 12; ++e)
    if (mc.edges[e].corner0 != kCubeEdgeLayout[e][0] || mc.edges[e].axis != kCubeEdgeLayout[e][1])
      throw std::logic_error("coarse_voxel_table: the marching cubes table's edges are not in kCubeEdgeLayout's order");
  CoarseVoxelTable t;
  for (unsigned cube_case = 0; cube_case < 256; ++cube_case) {
    int cut[12], n_cut = 0;
    for (int e = 0; e < 12; ++e)
      if (((cube_case >> mc.edges[e].corner0) & 1u) != ((cube_case >> mc.edges[e].corner1) & 1u)) cut[n_cut++] = e;
    t.first[cube_case] = static_cast<std::uint32_t>(t.entries.size());
    for (unsigned m = 0; m < 64; ++m)
      for (int r = 0; r < n_cut; ++r) {
        const int e = cut[r];
        if (e < 6 && ((m >> e) & 1u)) t.low[cube_case][m] |= static_cast<std::uint16_t>(1u << r);
        if (e >= 6 && ((m >> (e - 6)) & 1u)) t.high[cube_case][m] |= static_cast<std::uint16_t>(1u << r);
      }
    for (unsigned index = 0; index < (1u << n_cut); ++index) {
      unsigned corner[12] = {};
      for (int r = 0; r < n_cut; ++r) {
        const auto& ce = mc.edges[cut[r]];
        corner[cut[r]] = ((index >> r) & 1u) ? ce.corner1 : ce.corner0;
      }
      std::uint32_t tri[15];
      CornerTriangle facts[5];
      int n = 0;
      const auto& edges = mc.triangle_edges[cube_case];
      for (int k = 0; k < mc.triangle_count[cube_case]; ++k) {
        const unsigned a = corner[edges[3 * k]], b = corner[edges[3 * k + 1]], c = corner[edges[3 * k + 2]];
        if (a == b || b == c || a == c) continue;
        tri[3 * n] = a, tri[3 * n + 1] = b, tri[3 * n + 2] = c;
        facts[n++] = CornerTriangle(a, b, c);
      }
      int kept_index[5];
      const int kept = fold_within_voxel(tri, facts, n, kept_index);
      CoarseVoxel v = static_cast<CoarseVoxel>(kept) << kCoarseCountShift;
      for (int k = 0; k < kept; ++k) {
        v |= static_cast<CoarseVoxel>(tri[3 * k] | tri[3 * k + 1] << 3 | tri[3 * k + 2] << 6) << (9 * k);
        if (facts[kept_index[k]].on_face) v |= CoarseVoxel{1} << (kCoarseFaceShift + k);
      }
      t.entries.push_back(v);
    }
  }
  if (t.entries.size() > 65536) throw std::logic_error("coarse_voxel_table: entries do not fit a 16-bit index");
  for (unsigned c = 0; c < 512; ++c) {
    const unsigned a = c & 7u, b = (c >> 3) & 7u, d = c >> 6;
    if (a == b || b == d || a == d) continue;
    const CornerTriangle f(a, b, d);
    t.face_code[c] = f.on_face ? static_cast<std::uint8_t>(f.code | 0x80u) : 0;
  }
  return t;
}

}  // namespace

const CoarseVoxelTable& coarse_voxel_table() {
  static const CoarseVoxelTable table = build();
  return table;
}

}  // namespace keymesh::generate
