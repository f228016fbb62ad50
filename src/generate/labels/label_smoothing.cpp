// Smoothing of a welded label surface (see keymesh/generate/labels/labels.hpp).
//
// The stencil of every point is its neighbours along mesh edges, found by
// KEY-REDUCE: each directed edge is a pair keyed by its first point, the
// dense plan groups them, and a group (sorted, duplicates dropped) is the
// point's neighbour list. Iterations are Jacobi steps (every point moves from
// the previous iteration's positions, neighbours in increasing id), so the
// result does not depend on the thread count.
//
// Special points, handled explicitly:
//  - junctions (three or more labels meet: triple lines and their corners)
//    use only their junction neighbours, so a triple line is smoothed along
//    itself and is not pulled into any of the surfaces meeting there; a
//    junction point with fewer than two junction neighbours stays put;
//  - points on the padding around the grid (surfaces closed along the grid
//    border) keep their coordinate across that border plane, so the caps
//    stay flat, half a voxel outside the grid.
// Surface nets: Laplacian steps with the relaxation factor, each point then
// clamped to its cell (the box between its 8 samples), as vtkSurfaceNets3D
// constrains it. Discrete marching cubes: Taubin's lambda|mu steps
// (lambda = relaxation, mu chosen for a pass band of 0.1), which do not
// shrink the surface as plain Laplacian smoothing does. After every step the
// fold guard (label_fold_guard.cpp) shortens the moves that would turn a
// triangle over or flatten it, which the steps did where three or more
// labels meet (docs/decisions/labels-smoothing-folds.md).
#include <algorithm>
#include <cmath>

#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/generate/labels/label_kernels.hpp"
#include "label_fold_guard.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

struct Stencils {
  std::vector<Id> offsets;               // per point, into `neighbours`
  std::vector<std::uint32_t> neighbours;
};

Stencils build_stencils(const LabelSurface& s) {
  const auto& conn = s.mesh.connectivity;
  const Id points = static_cast<Id>(s.junction.size());
  // Directed edges, both ways: pair e runs from[e] -> to[e]. Surface nets
  // quads give their 4 sides (6 corners per quad), triangles their 3 edges.
  const int per = s.quads ? 4 : 3;
  const Id items = static_cast<Id>(conn.size()) / (s.quads ? 6 : 3);
  std::vector<std::uint32_t> from(static_cast<std::size_t>(2 * per * items)), to(from.size());
  parallel::for_each(items, [&](Id q) {
    static constexpr int quad_sides[4][2] = {{0, 1}, {1, 2}, {4, 5}, {5, 3}};
    static constexpr int tri_sides[3][2] = {{0, 1}, {1, 2}, {2, 0}};
    const std::uint32_t* c = conn.data() + q * (s.quads ? 6 : 3);
    for (int k = 0; k < per; ++k) {
      const int* side = s.quads ? quad_sides[k] : tri_sides[k];
      const std::size_t e = static_cast<std::size_t>(2 * (per * q + k));
      from[e] = c[side[0]], to[e] = c[side[1]];
      from[e + 1] = c[side[1]], to[e + 1] = c[side[0]];
    }
  });
  const auto groups = keyreduce::partition_dense(from.data(), static_cast<Id>(from.size()),
                                                 static_cast<std::uint32_t>(points), keyreduce::Order::Build);
  // Each group's neighbours sorted and deduplicated in place (in `to`'s
  // grouped copy), junctions keeping only their junction neighbours; then
  // counted, scanned and packed.
  std::vector<std::uint32_t> grouped(from.size());
  std::vector<Id> count(static_cast<std::size_t>(points + 1), 0);
  parallel::for_each(groups.num_groups(), [&](Id g) {
    const std::uint32_t p = groups.unique_keys[static_cast<std::size_t>(g)];
    std::uint32_t* b = grouped.data() + groups.offsets[g];
    std::uint32_t* e = grouped.data() + groups.offsets[g + 1];
    for (Id j = groups.offsets[g]; j < groups.offsets[g + 1]; ++j) grouped[static_cast<std::size_t>(j)] = to[groups.order[j]];
    std::sort(b, e);
    e = std::unique(b, e);
    if (s.junction[p]) {
      e = std::remove_if(b, e, [&](std::uint32_t q) { return !s.junction[q]; });
      if (e - b < 2) e = b;
    }
    count[p] = e - b;
  }, 256);
  Stencils st;
  st.offsets.assign(static_cast<std::size_t>(points + 1), 0);
  for (Id p = 0; p < points; ++p) st.offsets[p + 1] = st.offsets[p] + count[p];
  st.neighbours.resize(static_cast<std::size_t>(st.offsets[points]));
  parallel::for_each(groups.num_groups(), [&](Id g) {
    const std::uint32_t p = groups.unique_keys[static_cast<std::size_t>(g)];
    std::copy_n(grouped.data() + groups.offsets[g], count[p], st.neighbours.begin() + st.offsets[p]);
  }, 256);
  return st;
}

}  // namespace

Id smooth_label_surface(LabelSurface& s, const LabelVolume& vol, LabelMethod method, int iterations,
                        double relaxation) {
  const Id points = static_cast<Id>(s.junction.size());
  if (iterations <= 0 || points == 0) return 0;
  const Stencils st = build_stencils(s);
  FoldGuard guard(s);
  std::vector<double> x(s.mesh.points.begin(), s.mesh.points.end()), half(x.size()), candidate(x.size());
  const bool constrained = method == LabelMethod::SurfaceNets;
  label_kernels::SmoothStep step{st.offsets.data(), st.neighbours.data(), s.border_axes.data(),
                                 s.cell_centre.data(), {0.5 * vol.spacing[0], 0.5 * vol.spacing[1], 0.5 * vol.spacing[2]},
                                 constrained, 0.0, nullptr, nullptr};
  // One Jacobi step from `from` into `to`.
  auto run_step = [&](const std::vector<double>& from, std::vector<double>& to, double factor) {
    step.factor = factor, step.x = from.data(), step.next = to.data();
    parallel::for_each(points, [&](Id p) { step(p); }, 1024);
  };
  const double lambda = relaxation;
  const double mu = lambda / (0.1 * lambda - 1.0);  // 1/lambda + 1/mu = 0.1
  // The guard limits a whole iteration's move: Taubin's lambda and mu steps
  // guarded apart would shrink without the inflation that balances it.
  for (int it = 0; it < iterations; ++it) {
    if (constrained) {
      run_step(x, candidate, lambda);
    } else {
      run_step(x, half, lambda);
      run_step(half, candidate, mu);
    }
    guard.limit(x, candidate, half);
    x.swap(half);
  }
  for (std::size_t i = 0; i < x.size(); ++i) s.mesh.points[i] = static_cast<float>(x[i]);
  return guard.shortened();
}

Id smoothing_reach(const LabelOptions& options) {
  // An iteration's steps (Taubin: two) reach as many cells, and the guard
  // one more: a point's move is checked against its neighbours' candidates.
  const Id steps = options.method == LabelMethod::DiscreteMarchingCubes ? 2 : 1;
  return static_cast<Id>(options.smooth_iterations) * (steps + 1);
}

}  // namespace keymesh::generate::detail
