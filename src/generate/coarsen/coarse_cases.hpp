#pragma once
// The coarsened contour's triangles of one voxel, tabulated: what a voxel
// emits depends only on its cube case and, for each of its cut edges,
// whether the crossing is nearer the edge's far end (its coarse point is
// that corner). For every such pair the table holds the triangles kept, as
// corner triples in the cube case's triangle order: those with two equal
// corners dropped, and the folds decided within the voxel (coarse_folds.hpp:
// triangles off the voxel's faces over the same three corners). Face
// triangles are kept with their face code, for the decision across faces.
// 36,450 entries of 8 bytes (the sum over cube cases of 2^(cut edges)).
#include <array>
#include <cstdint>
#include <vector>

namespace keymesh::generate {

// The cube edges' order the far bits are read in (contour_coarse_rows.hpp)
// and MarchingCubesTable's (checked when the table is built): edge e starts
// at corner kCubeEdgeLayout[e][0] and runs along axis kCubeEdgeLayout[e][1].
constexpr std::uint8_t kCubeEdgeLayout[12][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 0},
                                                 {2, 2}, {3, 2}, {4, 0}, {4, 1}, {5, 1}, {6, 0}};

// A voxel's coarse triangles: triangle t's corners c0 | c1 << 3 | c2 << 6
// (x | y << 1 | z << 2) in bits [9 t, 9 t + 9), the count in bits 45-47,
// and in bits 48-52 which of them are face triangles (bit 48 + t), so that
// the tally pass visits only those. 8 bytes, so that the table (292 KB)
// stays in the second-level cache.
using CoarseVoxel = std::uint64_t;
constexpr int kCoarseCountShift = 45;
constexpr int kCoarseFaceShift = 48;

// A voxel's far key (contour_coarse_rows.hpp, VoxelRowFar): 16 bits read
// off its four corner rows' far bits (rows by corner bits y | z << 1), the
// far byte of its point i and that of point i + 1: bits 0-3 the x edges of
// rows 0-3 at i, bits 4-7 the y edge of row 0, the z edge of row 0, the y
// edge of row 2 and the z edge of row 1 at i, bits 8-11 the x edges at
// i + 1 (no edge of the voxel: never read), bits 12-15 the four of bits
// 4-7 at i + 1. Its cube edge by key bit (MarchingCubesTable's numbering,
// -1: none); coarse_voxel_table() checks it against kCubeEdgeLayout.
constexpr std::int8_t kFarKeyEdge[16] = {0, 5, 8, 11, 1, 2, 9, 6, -1, -1, -1, -1, 3, 4, 10, 7};

struct CoarseVoxelTable {
  std::vector<CoarseVoxel> entries;
  std::array<std::uint32_t, 256> first{};  // each cube case's first entry
  // The entry's index within its case is the far bits (bit e: edge e's
  // crossing is nearer its far end) of the case's cut edges, packed in
  // edge order. By the far key's three nibbles: x from bits 0-3 (plus the
  // case's first entry), here from bits 4-7, next from bits 12-15; a case's
  // 96 bytes are read together (24 KB for all cases).
  struct CaseIndex {
    std::uint16_t x[16], here[16], next[16];
  };
  std::array<CaseIndex, 256> by_case{};
  // By a triangle's 9 corner bits: CornerTriangle::code when its corners
  // lie on one face of the voxel, else 0 (the entry's face bits say which
  // triangles are on a face).
  std::array<std::uint8_t, 512> face_code{};

  // The entry of a voxel of this cube case and far key (below 2^16: there
  // are 36,450).
  std::uint16_t index(unsigned cube_case, unsigned far_key) const {
    const CaseIndex& c = by_case[cube_case];
    return static_cast<std::uint16_t>(c.x[far_key & 15u] + c.here[(far_key >> 4) & 15u] + c.next[far_key >> 12]);
  }
};

// Built once (thread-safe static initialisation).
// From marching_cubes_table(reversed_axes).
const CoarseVoxelTable& coarse_voxel_table(bool reversed_axes = false);

}  // namespace keymesh::generate
