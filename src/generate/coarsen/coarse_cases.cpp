#include "coarse_cases.hpp"

#include <algorithm>
#include <stdexcept>

#include "coarse_folds.hpp"
#include "keymesh/generate/contour/marching_cubes_table.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::generate {

namespace {

// A triangle's corner facts by its 9 corner bits (a | b << 3 | c << 6),
// and whether two of its corners are one (the triangle collapsed).
struct CornerTriangles {
  CornerTriangle facts[512];
  bool collapsed[512];
  CornerTriangles() {
    for (unsigned x = 0; x < 512; ++x) {
      const unsigned a = x & 7u, b = (x >> 3) & 7u, c = x >> 6;
      collapsed[x] = a == b || b == c || a == c;
      facts[x] = collapsed[x] ? CornerTriangle() : CornerTriangle(a, b, c);
    }
  }
};

// The entries of one cube case, from entries[t.first[cube_case]] on: each
// cut edge's coarse point is its near or far corner by the index's bit for
// it (the far bits of the case's cut edges, packed in edge order).
void build_case(const MarchingCubesTable& mc, const CornerTriangles& by_corners, unsigned cube_case,
                CoarseVoxelTable& t) {
  int n_cut = 0, rank[12];
  std::fill(rank, rank + 12, -1);
  for (int e = 0; e < 12; ++e)
    if (((cube_case >> mc.edges[e].corner0) & 1u) != ((cube_case >> mc.edges[e].corner1) & 1u))
      rank[e] = n_cut++;
  // Each nibble of the far key: the ranks of its cut edges' bits.
  auto packed = [&](unsigned m, int first_bit) {
    unsigned bits = 0;
    for (int b = 0; b < 4; ++b) {
      const int e = kFarKeyEdge[first_bit + b];
      if (((m >> b) & 1u) && rank[e] >= 0) bits |= 1u << rank[e];
    }
    return static_cast<std::uint16_t>(bits);
  };
  CoarseVoxelTable::CaseIndex& by_key = t.by_case[cube_case];
  for (unsigned m = 0; m < 16; ++m) {
    by_key.x[m] = static_cast<std::uint16_t>(t.first[cube_case] + packed(m, 0));
    by_key.here[m] = packed(m, 4), by_key.next[m] = packed(m, 12);
  }
  // Each marching cubes triangle's corners: its edges' ranks and ends.
  const int count = mc.triangle_count[cube_case];
  unsigned edge_rank[15], near[15], far[15];
  for (int x = 0; x < 3 * count; ++x) {
    const auto& ce = mc.edges[mc.triangle_edges[cube_case][x]];
    edge_rank[x] = static_cast<unsigned>(rank[mc.triangle_edges[cube_case][x]]);
    near[x] = ce.corner0, far[x] = ce.corner1;
  }
  CoarseVoxel* out = t.entries.data() + t.first[cube_case];
  for (unsigned index = 0; index < (1u << n_cut); ++index) {
    std::uint32_t tri[15];
    CornerTriangle facts[5];
    int n = 0;
    for (int k = 0; k < count; ++k) {
      unsigned x = 0;
      for (int c = 0; c < 3; ++c)
        x |= (((index >> edge_rank[3 * k + c]) & 1u) ? far[3 * k + c] : near[3 * k + c]) << (3 * c);
      if (by_corners.collapsed[x]) continue;
      tri[3 * n] = x & 7u, tri[3 * n + 1] = (x >> 3) & 7u, tri[3 * n + 2] = x >> 6;
      facts[n++] = by_corners.facts[x];
    }
    int kept_index[5];
    const int kept = fold_within_voxel(tri, facts, n, kept_index);
    CoarseVoxel v = static_cast<CoarseVoxel>(kept) << kCoarseCountShift;
    for (int k = 0; k < kept; ++k) {
      v |= static_cast<CoarseVoxel>(tri[3 * k] | tri[3 * k + 1] << 3 | tri[3 * k + 2] << 6) << (9 * k);
      if (facts[kept_index[k]].on_face) v |= CoarseVoxel{1} << (kCoarseFaceShift + k);
    }
    out[index] = v;
  }
}

// Every case's entries, the cases shared among the threads (a process pays
// this once, at its first coarsened contour: it was 17.5 M instructions on
// one thread).
CoarseVoxelTable build(const MarchingCubesTable& mc) {
  for (int e = 0; e < 12; ++e)
    if (mc.edges[e].corner0 != kCubeEdgeLayout[e][0] || mc.edges[e].axis != kCubeEdgeLayout[e][1])
      throw std::logic_error("coarse_voxel_table: the marching cubes table's edges are not in kCubeEdgeLayout's order");
  // The far key's bits: bits 0-3 x edges of corner rows 0-3, then y of row
  // 0, z of row 0, y of row 2, z of row 1; bits 12-15 those four at i + 1.
  constexpr int kKeyRow[16] = {0, 1, 2, 3, 0, 0, 2, 1, 0, 0, 0, 0, 0, 0, 2, 1};
  constexpr int kKeyAxis[16] = {0, 0, 0, 0, 1, 2, 1, 2, -1, -1, -1, -1, 1, 2, 1, 2};
  for (int b = 0; b < 16; ++b) {
    const int e = kFarKeyEdge[b];
    if ((e < 0) != (kKeyAxis[b] < 0) ||
        (e >= 0 && (kCubeEdgeLayout[e][0] != (b >= 12 ? 1 : 0) + 2 * kKeyRow[b] || kCubeEdgeLayout[e][1] != kKeyAxis[b])))
      throw std::logic_error("coarse_voxel_table: kFarKeyEdge does not match kCubeEdgeLayout");
  }
  CoarseVoxelTable t;
  std::size_t entries = 0;
  for (unsigned cube_case = 0; cube_case < 256; ++cube_case) {
    int n_cut = 0;
    for (int e = 0; e < 12; ++e)
      n_cut += ((cube_case >> mc.edges[e].corner0) & 1u) != ((cube_case >> mc.edges[e].corner1) & 1u);
    t.first[cube_case] = static_cast<std::uint32_t>(entries);
    entries += std::size_t{1} << n_cut;
  }
  if (entries > 65536) throw std::logic_error("coarse_voxel_table: entries do not fit a 16-bit index");
  t.entries.resize(entries);
  const CornerTriangles by_corners;
  parallel::for_each_dynamic(256, [&](Id cube_case) { build_case(mc, by_corners, static_cast<unsigned>(cube_case), t); }, 8);
  for (unsigned c = 0; c < 512; ++c)
    if (!by_corners.collapsed[c] && by_corners.facts[c].on_face)
      t.face_code[c] = by_corners.facts[c].code;
  return t;
}

}  // namespace

const CoarseVoxelTable& coarse_voxel_table(bool reversed_axes) {
  static const CoarseVoxelTable table = build(marching_cubes_table());
  if (!reversed_axes) return table;
  static const CoarseVoxelTable mirrored = build(marching_cubes_table(true));
  return mirrored;
}

}  // namespace keymesh::generate
