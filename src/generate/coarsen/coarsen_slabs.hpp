#pragma once
// The streamed contour's coarsening (contour --coarsen --memory-limit,
// issue 36), slab by slab: a coarse point (a grid point of the whole volume,
// + isovalue * N) is finished as soon as the slab above it has been read,
// so that only one slab's fine points and the carried crossings of its last
// plane are held, never the whole fine mesh.
//
// Why the bytes are coarsen()'s over the merged fine mesh (what the
// in-memory --coarsen writes): a coarse point averages its crossings in
// edge-key order (coarsening::group_mean's arithmetic). A grid point on plane
// z has crossings on the x and y edges of plane z and on the z edges to
// planes z - 1 and z + 1, so it is complete once a slab reaching plane z + 1
// has been read. A slab [k0, k_last] finishes the coarse points of planes
// k0 .. k_last - 1 (all of them at the last slab). Those of plane k_last wait
// for the next slab, which starts on that plane: it brings their x and y
// edges again (the same bits) and their upper z edges, so only the crossings
// of the z edges from plane k_last - 1 are carried. Their edge keys are below
// every key of the next slab, so carried-then-slab is edge-key order again.
// Coarse points are numbered per isovalue in key order (plane after plane),
// which is coarsen()'s order once the isovalues are put one after the other.
// A fine triangle becomes three coarse keys (dropped when two are equal, as
// coarsen() drops collapsed triangles); it is written as local ids once its
// points are numbered, and only the last voxel layer's triangles can wait,
// so the triangles keep their order. Folds are removed slab by slab too (a
// set of equal triangles lies in the voxel layers around its points). The
// non-manifold split and the removal of unused points then run on the
// coarse mesh (what is written), as coarsen() runs them: the split's rounds
// and the copies' numbers depend on the whole mesh
// (docs/decisions/coarsen-slab-by-slab.md).
#include <cstdint>
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::generate {

class SlabCoarsening {
 public:
  // dims: the whole grid's; isovalues: how many were contoured.
  SlabCoarsening(const Id dims[3], Id isovalues);

  // One slab's fine mesh over planes [k0, k_last] (ghost planes excluded),
  // its points in increasing global edge key `keys` (3 * grid point + axis
  // + isovalue * 3N) with their nearest grid points `nearest`
  // (contour(..., point_keys, nearest_keys)). `last`: no slab follows.
  void add_slab(const SurfaceMesh& fine, const std::vector<std::uint64_t>& keys,
                const std::vector<std::uint64_t>& nearest, Id k0, Id k_last, bool last);

  // After the last slab: the coarse mesh, folds removed, pinched points
  // split, unused points removed (coarsen()'s result).
  SurfaceMesh finish();

  Id fine_points() const { return fine_points_; }        // distinct fine points seen
  Id fine_triangles() const { return fine_triangles_; }  // the fine mesh's triangles
  Id most_fine_points_held() const { return most_held_; }  // a slab's and the carried ones, at most

 private:
  // Fine points in increasing edge key: their coarse keys, positions, fields.
  struct FinePoints {
    std::vector<std::uint64_t> nearest;
    std::vector<float> xyz;
    std::vector<std::vector<float>> fields;
    Id size() const { return static_cast<Id>(nearest.size()); }
  };
  // The coarse keys one slab finished, ascending; keys[i] has local id base + i.
  struct Finished {
    std::vector<std::uint64_t> keys;
    Id base = 0;
  };
  struct Isovalue {
    FinePoints carried;                    // z edges into the last plane read
    Array<float> xyz;                      // finished coarse points
    std::vector<Array<float>> fields;
    Array<PointIndex> triangles;           // local ids (within the isovalue)
    std::vector<std::uint64_t> waiting;    // triangles as coarse keys, 3 each
    Finished previous, current;
    Id fold_from = 0;                      // triangles from here on: folds not yet decided
  };
  struct SlabRange;

  void take_fields(const SurfaceMesh& fine);
  void finish_points(Isovalue& iso, const SlabRange& slab);
  void add_triangles(const SurfaceMesh& fine, const std::vector<std::uint64_t>& keys,
                     const std::vector<std::uint64_t>& nearest, Id k_last, bool last);
  void number_waiting(Isovalue& iso) const;
  void decide_folds(Isovalue& iso, Id iso_index, Id k_last, bool last) const;
  PointIndex local_id(const Isovalue& iso, std::uint64_t key) const;
  Id plane_of(std::uint64_t coarse_key) const;
  SurfaceMesh assemble();

  Id nxy_, points_per_iso_;
  std::vector<Field> field_shapes_;  // names and components, no values
  bool have_fields_ = false;
  std::vector<Isovalue> isos_;
  Id fine_points_ = 0, fine_triangles_ = 0, most_held_ = 0;
};

}  // namespace keymesh::generate
