#include "keymesh/mesh/keys.hpp"
#include "keymesh/analyze/incidence.hpp"

#include <algorithm>
#include <limits>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"

namespace keymesh::analyze {

namespace {

std::vector<std::uint32_t> cells_of_corners(const SurfaceMesh& m) {
  std::vector<std::uint32_t> cell(m.connectivity.size());
  parallel::for_each(m.num_cells(), [&](Id c) {
    for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k) cell[k] = static_cast<std::uint32_t>(c);
  });
  return cell;
}

}  // namespace

void check_ids(const SurfaceMesh& m) {
  if (m.connectivity.size() > std::numeric_limits<std::uint32_t>::max())
    throw LimitError("incidence: more than 2^32 - 1 corners");
  for (PointIndex id : m.connectivity)
    if (Id{id} >= m.num_points())
      throw InputError("incidence: a cell refers to point " + std::to_string(id) + " out of range");
}

PointCells point_cells(const SurfaceMesh& m) {
  check_ids(m);
  PointCells pc;
  if (!m.all_triangles()) pc.cell_of_corner = cells_of_corners(m);
  const Id n = static_cast<Id>(m.connectivity.size());
  // Groups keyed by point id; points no cell uses get empty groups, so the
  // dense plan's groups (present keys only) are spread over all points.
  auto g = keyreduce::partition_dense(m.connectivity.data(), n, static_cast<std::uint32_t>(m.num_points()),
                                      keyreduce::Order::Build);
  pc.offsets.assign(static_cast<std::size_t>(m.num_points() + 1), 0);
  for (Id k = 0; k < g.num_groups(); ++k) pc.offsets[g.unique_keys[k] + 1] = g.count(k);
  for (Id p = 0; p < m.num_points(); ++p) pc.offsets[p + 1] += pc.offsets[p];
  pc.corners = std::move(g.order);
  return pc;
}

std::vector<std::int64_t> cell_neighbours(const SurfaceMesh& m) {
  check_ids(m);
  const auto cell = cells_of_corners(m);
  const Id n = static_cast<Id>(m.connectivity.size());
  const EdgeKeys ek = EdgeKeys::for_points(m.num_points(), "incidence");
  std::vector<std::uint64_t> keys(static_cast<std::size_t>(n));
  parallel::for_each(m.num_cells(), [&](Id c) {
    const std::uint64_t b = m.cell_begin(c), e = m.cell_end(c);
    for (std::uint64_t k = b; k < e; ++k) {
      const std::uint64_t p = m.connectivity[k], q = m.connectivity[k + 1 < e ? k + 1 : b];
      keys[k] = ek(p, q);
    }
  });
  const auto g = keyreduce::partition_sort(keys.data(), n, ek.key_bits(), keyreduce::Order::Build);
  std::vector<std::int64_t> across(static_cast<std::size_t>(n), -1);
  parallel::for_each(g.num_groups(), [&](Id k) {
    const Id b = g.offsets[k], e = g.offsets[k + 1];
    if (e - b == 2) {
      across[g.order[b]] = cell[g.order[b + 1]];
      across[g.order[b + 1]] = cell[g.order[b]];
    } else if (e - b > 2) {
      for (Id j = b; j < e; ++j) across[g.order[j]] = -2;
    }
  });
  return across;
}

}  // namespace keymesh::analyze
