#include "keymesh/analyze/quality.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::analyze {

std::vector<double> triangle_quality(const SurfaceMesh& m) {
  const Id n = m.num_cells();
  for (Id c = 0; c < n && !m.all_triangles(); ++c)
    if (m.cell_end(c) - m.cell_begin(c) != 3)
      throw InputError("quality: cell " + std::to_string(c) + " is not a triangle");
  for (std::size_t k = 0; k < m.connectivity.size(); ++k)
    if (Id{m.connectivity[k]} >= m.num_points())
      throw InputError("quality: a cell refers to point " + std::to_string(m.connectivity[k]) + " out of range");
  std::vector<double> q(static_cast<std::size_t>(n));
  parallel::for_each(n, [&](Id t) {
    const std::uint64_t b = m.cell_begin(t);
    const float* p[3] = {&m.points[3 * std::size_t(m.connectivity[b])], &m.points[3 * std::size_t(m.connectivity[b + 1])],
                         &m.points[3 * std::size_t(m.connectivity[b + 2])]};
    double e[3][3], len2 = 0;
    for (int k = 0; k < 3; ++k)
      for (int x = 0; x < 3; ++x) e[k][x] = double(p[(k + 1) % 3][x]) - double(p[k][x]);
    for (int k = 0; k < 3; ++k) len2 += e[k][0] * e[k][0] + e[k][1] * e[k][1] + e[k][2] * e[k][2];
    const double c[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                         e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    const double area = 0.5 * std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    q[t] = len2 > 0 ? 4.0 * std::sqrt(3.0) * area / len2 : 0.0;
  });
  return q;
}

QualityReport quality(const SurfaceMesh& mesh) {
  std::vector<double> q = triangle_quality(mesh);
  QualityReport r;
  r.triangles = static_cast<Id>(q.size());
  if (q.empty()) return r;
  double sum = 0;
  Id above = 0;
  for (double v : q) {
    sum += v;
    above += v > 0.6;
    ++r.histogram[std::min<std::size_t>(9, static_cast<std::size_t>(std::max(0.0, v) * 10))];
  }
  r.mean = sum / double(q.size());
  r.fraction_above_0_6 = double(above) / double(q.size());
  std::sort(q.begin(), q.end());
  r.min = q.front();
  r.median = q.size() % 2 ? q[q.size() / 2] : 0.5 * (q[q.size() / 2 - 1] + q[q.size() / 2]);
  return r;
}

}  // namespace keymesh::analyze
