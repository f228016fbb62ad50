// The fold guard of label smoothing (see label_fold_guard.hpp).
//
// Why: the Laplacian steps fold the surface where three or more labels meet
// (a triangle turns over against its neighbour, or collapses), which a
// narrower clamp or junction stencils alone do not prevent (measured in
// docs/decisions/labels-smoothing-folds.md).
//
// The orientation of triangle (a, b, c) is D = ((b - a) x (c - a)) . n, n its
// unit normal before smoothing; unsmoothed D is twice its area. The guard
// keeps D >= kLeast x that on every triangle after every iteration, so no
// triangle turns over or gets thinner than kLeast of itself in the direction
// it faced.
// D is linear in each corner, so with a and its position fixed, D over b on
// the segment [x_b, candidate_b] and c on [x_c, candidate_c] is bilinear and
// least at one of the four ends' combinations: a point checks those, and its
// move is safe whatever fraction its neighbours take of theirs (a triangle
// none of whose corners moved is the previous step's). Each point decides
// from its own and its neighbours' candidates, so an iteration reaches one
// cell further than its steps (smoothing_reach), and the result is the same
// for any thread count. Guarding whole triangles keeps them from turning
// over; that sheets meeting at a junction do not cross each other is
// measured, not proven (the larger margin there).
//
// The per-triangle frame and the per-point step are label_kernels' GuardFrame
// and GuardStep, which the device path (labels_device.hpp) runs too: the
// same bits on every device. Here the step skips, on its first try, the
// triangles FoldClearance (label_fold_clearance.cpp) proves to pass: the
// same decisions, most of the tests saved.
#include "label_fold_guard.hpp"

#include <numeric>

#include "keymesh/generate/labels/label_kernels.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::generate::detail {

FoldGuard::FoldGuard(const LabelSurface& s) : corners_(s.mesh.connectivity) {
  const Id points = static_cast<Id>(s.junction.size());
  const Id triangles = static_cast<Id>(corners_.size() / 3);
  normal_.resize(static_cast<std::size_t>(3 * triangles));
  least_.resize(static_cast<std::size_t>(triangles));
  const label_kernels::GuardFrame frame{s.mesh.points.data(), corners_.data(), s.junction.data(), normal_.data(),
                                        least_.data()};
  parallel::for_each(triangles, [&](Id t) { frame(t); }, 1024);
  // Each point's corners: the corners grouped by point (KEY-REDUCE).
  const auto groups = keyreduce::partition_dense(corners_.data(), static_cast<Id>(corners_.size()),
                                                 static_cast<std::uint32_t>(points), keyreduce::Order::Build);
  std::vector<Id> count(static_cast<std::size_t>(points), 0);
  for (Id g = 0; g < groups.num_groups(); ++g) count[groups.unique_keys[static_cast<std::size_t>(g)]] = groups.count(g);
  offsets_.assign(static_cast<std::size_t>(points + 1), 0);
  for (Id p = 0; p < points; ++p) offsets_[p + 1] = offsets_[p] + count[p];
  point_corners_.resize(static_cast<std::size_t>(offsets_[points]));
  parallel::for_each(groups.num_groups(), [&](Id g) {
    const Id p = groups.unique_keys[static_cast<std::size_t>(g)];
    for (Id j = 0; j < groups.count(g); ++j)
      point_corners_[offsets_[p] + j] = static_cast<std::uint32_t>(groups.order[groups.offsets[g] + j]);
  }, 256);
  shortened_.assign(static_cast<std::size_t>(points), 0);
}

void FoldGuard::limit(const std::vector<double>& x, const std::vector<double>& candidate, std::vector<double>& out) {
  const Id points = static_cast<Id>(offsets_.size()) - 1;
  clearance_.update({corners_.data(), normal_.data(), least_.data(), x.data(), candidate.data(), points,
                     static_cast<Id>(least_.size())});
  const label_kernels::GuardStep step{corners_.data(), offsets_.data(), point_corners_.data(), normal_.data(),
                                      least_.data(), x.data(), candidate.data(), out.data(), shortened_.data(),
                                      clearance_.clear(), clearance_.clear_point()};
  parallel::for_each(points, [&](Id p) { step(p); }, 1024);
}

Id FoldGuard::shortened() const { return std::accumulate(shortened_.begin(), shortened_.end(), Id{0}); }

}  // namespace keymesh::generate::detail
