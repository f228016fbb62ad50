#include "keymesh/mesh/unused_points.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh {

namespace {

// The corners rewritten through `id` (each kept point's new id, n + 1
// entries: id[p + 1] != id[p] when p is kept), the points and point fields
// compacted into arrays of the exact size.
void renumber(SurfaceMesh& mesh, const std::vector<std::uint32_t>& id, Id kept) {
  const Id n = mesh.num_points(), corners = static_cast<Id>(mesh.connectivity.size());
  PointIndex* C = mesh.connectivity.data();
  parallel::for_each(corners, [&](Id c) { C[c] = id[C[c]]; }, 1 << 14);
  auto compact = [&](auto& values, int k) {
    std::remove_reference_t<decltype(values)> out;
    parallel::resize_fresh(out, static_cast<std::size_t>(kept * k));
    parallel::for_each(n, [&](Id p) {
      if (id[p + 1] != id[p])
        for (int a = 0; a < k; ++a) out[std::size_t{id[p]} * k + a] = values[std::size_t(p) * k + a];
    }, 1 << 14);
    values.swap(out);
  };
  compact(mesh.points, 3);
  for (Field& f : mesh.point_fields) compact(f.values, f.components);
}

}  // namespace

Id remove_unused_points(SurfaceMesh& mesh) {
  const Id n = mesh.num_points(), corners = static_cast<Id>(mesh.connectivity.size());
  if (n == 0) return 0;
  const PointIndex* C = mesh.connectivity.data();
  // id[p] = 1 when a corner holds p (several threads may store the same 1:
  // relaxed atomic stores, plain moves on every target), then (prefix sum)
  // each kept point's new id.
  std::vector<std::uint32_t> id;
  parallel::resize_fresh(id, static_cast<std::size_t>(n + 1));
  std::atomic<bool> out_of_range{false};
  parallel::for_each(corners, [&](Id c) {
    if (C[c] < n)
      std::atomic_ref<std::uint32_t>(id[C[c]]).store(1, std::memory_order_relaxed);
    else
      out_of_range.store(true, std::memory_order_relaxed);
  }, 1 << 14);
  if (out_of_range) throw InputError("remove_unused_points: a cell refers to a point past the mesh's " + std::to_string(n));
  const Id kept = parallel::exclusive_scan(id.data(), id.data(), n + 1);
  if (kept < n) renumber(mesh, id, kept);
  return n - kept;
}

void remove_points(SurfaceMesh& mesh, const std::vector<PointIndex>& unused) {
  if (unused.empty()) return;
  const Id n = mesh.num_points(), u = static_cast<Id>(unused.size());
  if (unused.back() >= n || !std::is_sorted(unused.begin(), unused.end()))
    throw InputError("remove_points: the points to remove must be ascending ids of the mesh");
  // Point p's new id: p less the removed points before it (a merge of the
  // points with the sorted list, by chunks).
  std::vector<std::uint32_t> id;
  parallel::resize_fresh(id, static_cast<std::size_t>(n + 1));
  parallel::for_each_chunk(n + 1, parallel::chunk_count(n + 1, 1 << 16), [&](Id b, Id e, int) {
    Id before = std::lower_bound(unused.begin(), unused.end(), static_cast<PointIndex>(b)) - unused.begin();
    for (Id p = b; p < e; ++p) {
      id[p] = static_cast<std::uint32_t>(p - before);
      if (before < u && unused[before] == p) ++before;
    }
  });
  renumber(mesh, id, n - u);
}

}  // namespace keymesh
