#include "keymesh/mesh/normals.hpp"

#include <algorithm>
#include <utility>

#include "keymesh/core/error.hpp"

namespace keymesh {

namespace {
void require_triangles(const SurfaceMesh& mesh) {
  if (!mesh.all_triangles()) throw InputError("normals: the mesh has polygons; only triangles are averaged");
}
}  // namespace

std::vector<Vec3f> face_normals(const SurfaceMesh& mesh) {
  require_triangles(mesh);
  std::vector<Vec3f> face(static_cast<std::size_t>(mesh.num_cells()));
  const float* P = mesh.points.data();
  const PointIndex* C = mesh.connectivity.data();
  parallel::for_each(mesh.num_cells(), [&](Id t) { face[t] = triangle_normal(P, C, t); });
  return face;
}

std::vector<Vec3f> point_normal_sums(const SurfaceMesh& mesh) {
  const std::vector<Vec3f> face = face_normals(mesh);
  // Corners grouped by point: the connectivity is the index map, the
  // points are the groups (a point no corner names is an empty group).
  keyreduce::Groups<PointIndex> corners;
  corners.index_map = mesh.connectivity;
  corners.unique_keys.resize(static_cast<std::size_t>(mesh.num_points()));
  keyreduce::build_order(corners);
  std::vector<Vec3f> sums(static_cast<std::size_t>(mesh.num_points()));
  sum_face_normals(corners, face.data(), sums.data());
  return sums;
}

void normalize(Vec3f* v, Id n) {
  parallel::for_each(n, [&](Id i) { v[i] = unit(v[i]); });
}

Field normals_field(const std::vector<Vec3f>& v) {
  Field n{"Normals", 3, Array<float>(3 * v.size())};
  std::copy_n(reinterpret_cast<const float*>(v.data()), n.values.size(), n.values.data());
  return n;
}

void average_normals(SurfaceMesh& mesh) {
  std::vector<Vec3f> sums = point_normal_sums(mesh);
  normalize(sums.data(), static_cast<Id>(sums.size()));
  Field n = normals_field(sums);
  for (Field& f : mesh.point_fields)
    if (f.name == "Normals") {
      f = std::move(n);
      return;
    }
  mesh.point_fields.push_back(std::move(n));
}

}  // namespace keymesh
