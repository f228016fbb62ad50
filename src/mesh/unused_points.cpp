#include "keymesh/mesh/unused_points.hpp"

#include <atomic>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "keymesh/parallel/fresh_memory.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh {

Id remove_unused_points(SurfaceMesh& mesh) {
  const Id n = mesh.num_points(), corners = static_cast<Id>(mesh.connectivity.size());
  if (n == 0) return 0;
  PointIndex* C = mesh.connectivity.data();
  // used[p] = 1 when a corner holds p (several threads may store the same 1:
  // relaxed atomic stores, plain moves on every target).
  std::vector<std::uint32_t> id;  // used, then (prefix sum) each used point's new id
  parallel::resize_fresh(id, static_cast<std::size_t>(n + 1));
  parallel::for_each(corners, [&](Id c) {
    std::atomic_ref<std::uint32_t>(id[C[c]]).store(1, std::memory_order_relaxed);
  }, 1 << 14);
  const Id kept = parallel::exclusive_scan(id.data(), id.data(), n + 1);
  if (kept == n) return 0;
  auto used = [&](Id p) { return id[p + 1] != id[p]; };
  parallel::for_each(corners, [&](Id c) { C[c] = id[C[c]]; }, 1 << 14);
  auto compact = [&](auto& values, int k) {
    std::remove_reference_t<decltype(values)> out;
    parallel::resize_fresh(out, static_cast<std::size_t>(kept * k));
    parallel::for_each(n, [&](Id p) {
      if (used(p))
        for (int a = 0; a < k; ++a) out[std::size_t{id[p]} * k + a] = values[std::size_t(p) * k + a];
    }, 1 << 14);
    values.swap(out);
  };
  compact(mesh.points, 3);
  for (Field& f : mesh.point_fields) compact(f.values, f.components);
  return n - kept;
}

}  // namespace keymesh
