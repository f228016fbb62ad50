#include "keymesh/mesh/unit_normals.hpp"

#include <cmath>
#include <cstdint>
#include <vector>

#include "keymesh/mesh/face_normal.hpp"

namespace keymesh {

namespace {
bool defined(Vec3f v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && (v.x != 0 || v.y != 0 || v.z != 0);
}
}  // namespace

Id make_unit_normals(const SurfaceMesh& mesh, float* normals) {
  auto* v = reinterpret_cast<Vec3f*>(normals);
  const Id points = mesh.num_points();
  std::vector<std::uint8_t> undefined(static_cast<std::size_t>(points), 0);
  Id changed = 0;
  for (Id p = 0; p < points; ++p) {
    const Vec3f n = v[p];
    if (!defined(n)) {
      undefined[p] = 1, ++changed;
      continue;
    }
    const double len = std::sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z);
    if (std::fabs(len - 1) > 1e-4) {  // in double: no square of a tiny or huge float underflows or overflows
      v[p] = Vec3f{static_cast<float>(n.x / len), static_cast<float>(n.y / len), static_cast<float>(n.z / len)};
      ++changed;
    }
  }
  if (!changed) return 0;
  // The cells with an undefined corner: the only ones the rounds look at.
  std::vector<Id> cells;
  for (Id c = 0; c < mesh.num_cells(); ++c)
    for (std::uint64_t k = mesh.cell_begin(c); k < mesh.cell_end(c); ++k)
      if (undefined[mesh.connectivity[k]]) {
        cells.push_back(c);
        break;
      }
  std::vector<Vec3f> sum(static_cast<std::size_t>(points));
  for (bool progress = true; progress;) {
    for (Id c : cells)
      for (std::uint64_t k = mesh.cell_begin(c); k < mesh.cell_end(c); ++k) sum[mesh.connectivity[k]] = {0, 0, 0};
    for (Id c : cells)
      for (std::uint64_t k = mesh.cell_begin(c); k < mesh.cell_end(c); ++k) {
        const PointIndex p = mesh.connectivity[k];
        if (!undefined[p]) continue;
        for (std::uint64_t j = mesh.cell_begin(c); j < mesh.cell_end(c); ++j)
          if (!undefined[mesh.connectivity[j]]) sum[p] = add(sum[p], v[mesh.connectivity[j]]);
      }
    progress = false;
    std::vector<PointIndex> now_defined;
    for (Id c : cells)
      for (std::uint64_t k = mesh.cell_begin(c); k < mesh.cell_end(c); ++k) {
        const PointIndex p = mesh.connectivity[k];
        if (undefined[p] && defined(unit(sum[p]))) {
          v[p] = unit(sum[p]);
          now_defined.push_back(p);
        }
      }
    for (PointIndex p : now_defined) undefined[p] = 0, progress = true;
  }
  for (Id p = 0; p < points; ++p)
    if (undefined[p]) v[p] = Vec3f{0, 0, 1};
  return changed;
}

}  // namespace keymesh
