#include "keymesh/generate/coarsen/coarsen.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/generate/contour/contour_kernels.hpp"
#include "keymesh/generate/coarsen/coarsen_kernels.hpp"
#include "keymesh/generate/coarsen/split_nonmanifold.hpp"
#include "keymesh/mesh/unused_points.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh::generate {

using coarsening::TriangleSet;
using coarsening::triangle_set;

namespace {

// Which of n triangles the folds remove (drop[t] = 1), grouped by their
// smallest point id (KEY-REDUCE, sort plan), each group's few triangles
// compared with one another; of every set of equal triangles the first of
// the winning orientation is kept when the orientations do not cancel.
// False when no set repeats (drop then all 0).
bool folded_triangles(const PointIndex* C, Id n, Id num_points, std::vector<std::uint8_t>& drop) {
  std::vector<TriangleSet> tri(static_cast<std::size_t>(n));
  std::vector<std::uint32_t> lo(static_cast<std::size_t>(n));
  parallel::for_each(n, [&](Id t) {
    tri[t] = triangle_set(C, t);
    lo[t] = tri[t].lo;
  });
  const auto g = keyreduce::partition_sort(lo.data(), n, parallel::bits_needed<std::uint32_t>(
                                                             static_cast<std::uint32_t>(num_points - 1)),
                                           keyreduce::Order::Build);
  drop.assign(static_cast<std::size_t>(n), 0);
  std::vector<std::uint8_t> folded_any(static_cast<std::size_t>(g.num_groups()), 0);
  parallel::for_each(g.num_groups(), [&](Id grp) {
    const Id b = g.offsets[grp], e = g.offsets[grp + 1];
    for (Id i = b; i < e; ++i) {
      const TriangleSet& ti = tri[g.order[i]];
      bool first = true;
      for (Id j = b; j < i && first; ++j)
        first = !(tri[g.order[j]].mid == ti.mid && tri[g.order[j]].hi == ti.hi);
      if (!first) continue;  // decided with the first of its set
      int net = ti.sign, copies = 1;
      for (Id j = i + 1; j < e; ++j)
        if (tri[g.order[j]].mid == ti.mid && tri[g.order[j]].hi == ti.hi) net += tri[g.order[j]].sign, ++copies;
      if (copies == 1) continue;
      folded_any[grp] = 1;
      bool kept = false;
      for (Id j = i; j < e; ++j) {
        const TriangleSet& tj = tri[g.order[j]];
        if (tj.mid != ti.mid || tj.hi != ti.hi) continue;
        const bool winner = net != 0 && !kept && (tj.sign > 0) == (net > 0);
        drop[g.order[j]] = winner ? 0 : 1;
        kept = kept || winner;
      }
    }
  });
  return std::find(folded_any.begin(), folded_any.end(), 1) != folded_any.end();
}

}  // namespace

Id remove_folds(SurfaceMesh& mesh) {
  const Id n = mesh.num_cells();
  if (n == 0) return 0;
  std::vector<std::uint8_t> drop;
  if (!folded_triangles(mesh.connectivity.data(), n, mesh.num_points(), drop)) return 0;
  // Pack the kept triangles and their cell fields' tuples in place, in
  // order (each moves to a lower index).
  Id at = 0;
  PointIndex* W = mesh.connectivity.data();
  for (Id t = 0; t < n; ++t) {
    if (drop[t]) continue;
    if (at != t) {
      for (int k = 0; k < 3; ++k) W[3 * at + k] = W[3 * t + k];
      for (Field& f : mesh.cell_fields)
        std::copy_n(f.values.begin() + t * f.components, f.components, f.values.begin() + at * f.components);
    }
    ++at;
  }
  mesh.connectivity.resize(static_cast<std::size_t>(3 * at));
  for (Field& f : mesh.cell_fields) f.values.resize(static_cast<std::size_t>(at * f.components));
  return n - at;
}

Id remove_complete_folds(Array<PointIndex>& connectivity, Id first_triangle, PointIndex complete_below) {
  const Id n = static_cast<Id>(connectivity.size() / 3) - first_triangle;
  PointIndex* W = connectivity.data() + 3 * first_triangle;
  const PointIndex top = n > 0 ? *std::max_element(W, W + 3 * n) : 0;
  std::vector<std::uint8_t> drop;
  const bool folds = n > 0 && folded_triangles(W, n, static_cast<Id>(top) + 1, drop);
  auto complete = [&](Id t) {
    return W[3 * t] < complete_below && W[3 * t + 1] < complete_below && W[3 * t + 2] < complete_below;
  };
  Id at = 0, left = -1;
  for (Id t = 0; t < n; ++t) {
    if (folds && drop[t] && complete(t)) continue;
    if (left < 0 && !complete(t)) left = at;
    for (int k = 0; k < 3; ++k) W[3 * at + k] = W[3 * t + k];
    ++at;
  }
  connectivity.resize(static_cast<std::size_t>(3 * (first_triangle + at)));
  return first_triangle + (left < 0 ? at : left);
}

void check_coarsen_input(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys, std::uint64_t key_range) {
  if (!mesh.all_triangles()) throw InputError("coarsen: the mesh has polygons; only triangles are coarsened");
  if (static_cast<Id>(keys.size()) != mesh.num_points()) throw InputError("coarsen: one key per point is needed");
  // The sort plan reads only the range's bits: a key past it would merge
  // with another instead of being refused.
  const auto past = std::find_if(keys.begin(), keys.end(), [&](std::uint64_t k) { return k >= key_range; });
  if (past != keys.end())
    throw InputError("coarsen: point " + std::to_string(past - keys.begin()) + "'s key " + std::to_string(*past) +
                     " is outside the key range [0, " + std::to_string(key_range) + ")");
}

namespace {

// coarsen()'s work; with `rounds`, the split's rounds agreed with the other
// parts and what it did returned in `split` (unused points left in place).
SurfaceMesh coarsen_mesh(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys, std::uint64_t key_range,
                         CoarsenStats* stats, const SplitRounds* rounds, NonmanifoldSplit* split) {
  check_coarsen_input(mesh, keys, key_range);
  const Id n = mesh.num_points();
  // The dense plan's table spans the key range (every grid point of the
  // volume, for a contour); past a few keys per point the sort plan (same
  // groups, same order) touches far less memory.
  const auto groups = key_range <= static_cast<std::uint64_t>(4 * n + 1024)
                          ? keyreduce::partition_dense(keys.data(), n, key_range, keyreduce::Order::Build)
                          : keyreduce::partition_sort(keys.data(), n, parallel::bits_needed<std::uint64_t>(key_range - 1),
                                                      keyreduce::Order::Build);
  const Id m = groups.num_groups();
  SurfaceMesh out;
  // Positions and every field: the mean over the group, in pair order.
  auto average = [&](const Array<float>& in, int k, Array<float>& dst) {
    dst.assign(static_cast<std::size_t>(m * k), 0.f);
    parallel::for_each(m, [&](Id g) {
      for (int c = 0; c < k; ++c) {
        dst[g * k + c] = coarsening::group_mean(in.data(), k, c, groups.order.data(), groups.offsets[g], groups.offsets[g + 1]);
      }
    });
  };
  average(mesh.points, 3, out.points);
  for (const Field& f : mesh.point_fields) {
    Field h{f.name, f.components, {}};
    average(f.values, f.components, h.values);
    if (f.name == "Normals" && f.components == 3)
      parallel::for_each(m, [&](Id g) { coarsening::renormalize(&h.values[3 * g]); });
    out.point_fields.push_back(std::move(h));
  }
  // Rewrite the triangles through the index map; keep those with three distinct points.
  const Id t_in = mesh.num_cells();
  std::vector<Id> keep(static_cast<std::size_t>(t_in + 1), 0);
  const PointIndex* C = mesh.connectivity.data();
  const std::uint32_t* map = groups.index_map.data();
  parallel::for_each(t_in, [&](Id t) {
    const std::uint32_t a = map[C[3 * t]], b = map[C[3 * t + 1]], c = map[C[3 * t + 2]];
    keep[t] = coarsening::distinct(a, b, c) ? 1 : 0;
  });
  const Id t_out = parallel::exclusive_scan(keep.data(), keep.data(), t_in + 1);
  out.connectivity.resize(static_cast<std::size_t>(3 * t_out));
  for (const Field& f : mesh.cell_fields) out.cell_fields.push_back(Field{f.name, f.components, {}});
  for (Field& f : out.cell_fields) f.values.resize(static_cast<std::size_t>(t_out * f.components));
  parallel::for_each(t_in, [&](Id t) {
    if (keep[t + 1] == keep[t]) return;
    for (int k = 0; k < 3; ++k) out.connectivity[3 * keep[t] + k] = map[C[3 * t + k]];
    for (std::size_t i = 0; i < out.cell_fields.size(); ++i) {
      const int k = out.cell_fields[i].components;
      std::copy_n(mesh.cell_fields[i].values.begin() + t * k, k, out.cell_fields[i].values.begin() + keep[t] * k);
    }
  });
  const Id folded = remove_folds(out);
  if (rounds)
    *split = split_nonmanifold_part(out, *rounds);
  else
    remove_points(out, split_nonmanifold(out).unused);
  if (stats) *stats = CoarsenStats{n, out.num_points(), t_in, t_out - folded, folded};
  return out;
}

}  // namespace

SurfaceMesh coarsen(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys, std::uint64_t key_range,
                    CoarsenStats* stats) {
  return coarsen_mesh(mesh, keys, key_range, stats, nullptr, nullptr);
}

SurfaceMesh coarsen_part(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys, std::uint64_t key_range,
                         const SplitRounds& rounds, NonmanifoldSplit& split) {
  return coarsen_mesh(mesh, keys, key_range, nullptr, &rounds, &split);
}

}  // namespace keymesh::generate
