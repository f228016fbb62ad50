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

struct CoarseVoxelTable {
  std::vector<CoarseVoxel> entries;
  std::array<std::uint32_t, 256> first{};  // each cube case's first entry
  // The entry's index within its case: far bits (bit e = edge e's crossing
  // is nearer its far end; edges in MarchingCubesTable order) of the case's
  // cut edges, packed in edge order; by the far bits of edges 0-5 and 6-11.
  std::array<std::array<std::uint16_t, 64>, 256> low{}, high{};
  // By a triangle's 9 corner bits: CornerTriangle::code | 0x80 when its
  // corners lie on one face of the voxel, else 0.
  std::array<std::uint8_t, 512> face_code{};

  // The entry of a voxel of this cube case and far bits (below 2^16: there
  // are 36,450).
  std::uint16_t index(unsigned cube_case, unsigned far) const {
    return static_cast<std::uint16_t>(first[cube_case] + low[cube_case][far & 63u] + high[cube_case][far >> 6]);
  }
};

// Built once (thread-safe static initialisation).
const CoarseVoxelTable& coarse_voxel_table();

}  // namespace keymesh::generate
