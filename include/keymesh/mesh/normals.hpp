#pragma once
// Surface normals, one place for every generator (PMP's normals.h is the
// model): the face normal formula, and point normals as KEY-REDUCE over the
// corners grouped by point: merge = sum of the area-weighted face normals,
// transform = normalise. The corners of a point are summed from zero in
// increasing corner order (triangle order), so a point's bytes depend on the
// mesh alone, at any thread count, and a streamed or distributed contour
// that sums per slab or per rank and adds the partial sums gets the same
// merge, only associated differently.
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/mesh/face_normal.hpp"
#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh {

// Every triangle's area-weighted normal (triangles only).
std::vector<Vec3f> face_normals(const SurfaceMesh& mesh);

// out[g] = the sum, from zero, of face[pair / 3] over group g's pairs in
// increasing order: `corners` groups a triangle mesh's corners (pair
// 3t + k) by point, e.g. a weld's groups, or build_order over the
// connectivity.
template <class K>
void sum_face_normals(const keyreduce::Groups<K>& corners, const Vec3f* face, Vec3f* out) {
  const Id* offsets = corners.offsets.data();
  const std::uint32_t* order = corners.order.data();
  parallel::for_each(corners.num_groups(), [&](Id g) {
    Vec3f s{0, 0, 0};
    for (Id j = offsets[g]; j < offsets[g + 1]; ++j) s = add(s, face[order[j] / 3]);
    out[g] = s;
  }, 1024);
}

// out[p] = point p's sum, from zero, of the normals of its triangles in
// increasing corner order (the merge without the transform: the bytes of a
// serial scatter over the triangles); a point no triangle uses gets zero.
// out holds num_points() elements. Triangles only (InputError otherwise).
void sum_point_normals(const SurfaceMesh& mesh, Vec3f* out);

// The same, returned.
std::vector<Vec3f> point_normal_sums(const SurfaceMesh& mesh);

// The transform over an array: v[i] = unit(v[i]).
void normalize(Vec3f* v, Id n);

// The point field "Normals" holding v.
Field normals_field(const std::vector<Vec3f>& v);

// Sets (or replaces) the point field "Normals" of a triangle mesh: the unit
// sum of the area-weighted normals of each point's triangles.
void average_normals(SurfaceMesh& mesh);

}  // namespace keymesh
