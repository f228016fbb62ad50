#include "keymesh/generate/contour/layer_blocks.hpp"

#include <algorithm>

#include "keymesh/keyreduce/reduce.hpp"
#include "keymesh/mesh/face_normal.hpp"
#include "keymesh/mesh/normals.hpp"

namespace keymesh::generate {

std::vector<Id> layer_blocks(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& point_keys, const LayerGrid& grid) {
  const std::uint64_t per_iso = 3 * grid.nxy * static_cast<std::uint64_t>(grid.layers + 1);
  const PointIndex* C = mesh.connectivity.data();
  const Id triangles = mesh.num_cells();
  // A triangle's layer is its corners' lowest plane: every marching cubes
  // triangle has a corner on its voxel's bottom face or on a z edge from it.
  auto layer_of = [&](Id t) {
    std::uint64_t plane = ~std::uint64_t{0};
    for (int c = 0; c < 3; ++c) plane = std::min(plane, point_keys[C[3 * t + c]] % per_iso / 3 / grid.nxy);
    return static_cast<Id>(plane);
  };
  std::vector<Id> blocks;
  Id t = 0;
  for (Id iso = 0; iso < grid.isovalues; ++iso) {
    auto in_iso = [&](Id u) { return static_cast<Id>(point_keys[C[3 * u]] / per_iso) == iso; };
    for (Id k = 0; k < grid.layers; k += kSlabsPerBlock) {
      while (t < triangles && in_iso(t) && layer_of(t) < k) ++t;
      blocks.push_back(3 * t);
    }
    while (t < triangles && in_iso(t)) ++t;
  }
  blocks.push_back(3 * triangles);
  return blocks;
}

void sum_blocked_normals(const SurfaceMesh& mesh, const std::vector<Id>& blocks, Vec3f* out) {
  const float* P = mesh.points.data();
  const PointIndex* C = mesh.connectivity.data();
  // The three corners of a triangle share its face normal (arity 3).
  keyreduce::reduce_blocked(C, blocks.data(), static_cast<Id>(blocks.size()) - 1, 3,
                            [P, C](Id t) { return triangle_normal(P, C, t); }, add, Vec3f{0, 0, 0}, out,
                            mesh.num_points());
}

Field blocked_average_normals(const SurfaceMesh& mesh, const std::vector<Id>& blocks) {
  Field n{"Normals", 3, Array<float>(static_cast<std::size_t>(3 * mesh.num_points()))};
  auto* out = reinterpret_cast<Vec3f*>(n.values.data());
  sum_blocked_normals(mesh, blocks, out);
  normalize(out, mesh.num_points());
  return n;
}

}  // namespace keymesh::generate
