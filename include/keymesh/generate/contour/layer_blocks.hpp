#pragma once
// The order in which one in-memory contour sums a point's face normals
// (--normals average), and those normals for a mesh assembled elsewhere.
//
// contour() hands keyreduce::reduce_blocked the triangles in blocks of
// kSlabsPerBlock voxel layers per isovalue, even blocks before odd ones, so a
// point on a plane between two blocks adds the even block's triangles first.
// A mesh merged from slabs (--memory-limit) or ranks (mpirun) has the same
// triangles in the same order and knows each point's global edge key, hence
// each triangle's voxel layer: it can cut the same blocks and sum in the same
// order, bit for bit, where adding each part's partial sums would not.
#include <cstdint>
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/mesh/face_normal.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::generate {

// Voxel layers per block: a constant, so the blocks (and the merge order
// they imply) do not depend on the thread count, slab size or rank count.
constexpr Id kSlabsPerBlock = 4;

struct LayerGrid {
  std::uint64_t nxy = 0;  // points per plane of the whole grid
  Id layers = 0;          // voxel layers of the whole grid (nz - 1)
  Id isovalues = 0;
};

// The corner index where each block starts, per isovalue, ending with the
// corner count: what contour() passes to reduce_blocked. `point_keys`:
// each point's global edge key (isovalue * 3 nxy nz + 3 grid point + axis).
std::vector<Id> layer_blocks(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& point_keys, const LayerGrid& grid);

// Face normals summed per point from zero by reduce_blocked over `blocks`
// (corner offsets, ending with the corner count), not yet made unit: the
// sums contour() makes for --normals average.
void sum_blocked_normals(const SurfaceMesh& mesh, const std::vector<Id>& blocks, Vec3f* out);

// The "Normals" field contour() would write for this mesh: those sums, made unit.
Field blocked_average_normals(const SurfaceMesh& mesh, const std::vector<Id>& blocks);

}  // namespace keymesh::generate
