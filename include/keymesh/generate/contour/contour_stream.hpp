#pragma once
// Out-of-core marching cubes (issue 9): the volume is read in slabs of
// z-planes that fit a memory limit, each slab is contoured with *global* edge
// keys (3 * point id of the whole grid + axis), and one KEY-REDUCE over the
// slabs' points merges the points of the planes two slabs share. The merge
// needs no spatial search and the output is byte-identical to contouring the
// whole volume at once: the same keys give the same point order, the slabs
// give the triangles in voxel order, and a shared plane's points are
// computed from the same samples by both slabs.
//
// Supported: any scalar type, several isovalues, the interpolated scalar,
// gradient normals and mean curvature (each slab reads a ghost plane on
// either side for the central differences, so they too are bit-identical).
// Averaged normals: summed over the merged mesh in the in-memory run's
// blocks of voxel layers (generate/layer_blocks.hpp): bit-identical.
// Coarsening: the slabs' fine points carry their nearest grid points (the
// coarse keys); a coarse point is finished as soon as the slab above it has
// been read (coarsen/coarsen_slabs.hpp), so only a slab's fine points and the
// crossings carried into the next are held, never the whole fine mesh. The
// coarse mesh (the output) then has its folds removed and its pinched points
// split as coarsen() does: byte-identical to the in-memory --coarsen,
// averaged normals included (computed from the coarse mesh).
// History (options.history): the slabs' history_t field, merged as every
// field is; point_keys, when given, receives the merged points' global edge
// keys (history_key). Refused by name for now: the GPU.
#include <cstddef>
#include <memory>
#include <vector>

#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/mesh/plane_source.hpp"

namespace keymesh::generate {

struct StreamStats {
  Id slabs = 0;
  Id planes_per_slab = 0;
  std::size_t slab_bytes = 0;   // samples held at once
  double read = 0, contour = 0, merge = 0;
  // Fine points: distinct ones seen (with coarsen), and the most held at
  // once (with coarsen a slab's and the carried ones; without, all of them).
  Id fine_points = 0, most_fine_points_held = 0;
};

// memory_limit: bytes for the samples held at once (at least two planes);
// the output mesh comes on top. Throws InputError for unsupported options,
// LimitError when two planes do not fit the limit.
SurfaceMesh contour_streamed(PlaneSource& source, const ContourOptions& options, std::size_t memory_limit,
                             ContourStats* stats = nullptr, StreamStats* stream_stats = nullptr,
                             std::vector<std::uint64_t>* point_keys = nullptr);

// Planes [lo, hi] of the grid (lo < hi; ghost planes outside them read
// where the grid has them and the options need them), streamed under
// `memory_limit` and merged: the mesh, global edge keys (`keys`) and, when
// given, nearest grid points that contour() of that slab with global keys
// gives (first_plane, total_planes and ghosts set as for a distributed
// rank). For a rank of the distributed contour under --memory-limit.
// Fine points only: options.coarsen and averaged normals are the caller's.
SurfaceMesh contour_planes_streamed(PlaneSource& source, const ContourOptions& options, std::size_t memory_limit,
                                    Id lo, Id hi, std::vector<std::uint64_t>& keys,
                                    std::vector<std::uint64_t>* nearest = nullptr, StreamStats* stream_stats = nullptr);

}  // namespace keymesh::generate
