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
#include "label_fold_guard.hpp"

#include <cmath>

#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::generate::detail {

namespace {

// The least orientation kept, as a fraction of the unsmoothed one: 0.05 in
// general, 0.5 on triangles with a junction corner (three or more labels
// meet), where 0.05 still let triangles of sheets meeting there cross (and
// 0.4 did on one of 30 noise volumes; measured in the decision record).
constexpr double kLeast = 0.05;
constexpr double kLeastJunction = 0.5;
constexpr double kFractions[4] = {1.0, 0.5, 0.25, 0.125};

// Two doubles, one per lane of an SSE2 register: two of a triangle's four
// end combinations at once, each lane the scalar operations in the scalar
// order (no contraction: -ffp-contract=off), so the same bits as one by one.
using Pair = double __attribute__((vector_size(16)));

// ((q - p) x (r - p)) . n for r at both ends r0, r1 (the lanes).
Pair orientations(const double* p, const double* q, const double* r0, const double* r1, const double* n) {
  const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const Pair v[3] = {Pair{r0[0], r1[0]} - p[0], Pair{r0[1], r1[1]} - p[1], Pair{r0[2], r1[2]} - p[2]};
  return (u[1] * v[2] - u[2] * v[1]) * n[0] + (u[2] * v[0] - u[0] * v[2]) * n[1] + (u[0] * v[1] - u[1] * v[0]) * n[2];
}

}  // namespace

FoldGuard::FoldGuard(const LabelSurface& s) : corners_(s.mesh.connectivity) {
  const Id points = static_cast<Id>(s.junction.size());
  const Id triangles = static_cast<Id>(corners_.size() / 3);
  normal_.resize(static_cast<std::size_t>(3 * triangles));
  least_.resize(static_cast<std::size_t>(triangles));
  parallel::for_each(triangles, [&](Id t) {
    double c[3][3];
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) c[k][a] = s.mesh.points[3 * static_cast<Id>(corners_[3 * t + k]) + a];
    const double u[3] = {c[1][0] - c[0][0], c[1][1] - c[0][1], c[1][2] - c[0][2]};
    const double v[3] = {c[2][0] - c[0][0], c[2][1] - c[0][1], c[2][2] - c[0][2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double twice_area = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    // A triangle degenerate unsmoothed keeps a zero normal: its corners stay.
    for (int a = 0; a < 3; ++a) normal_[3 * t + a] = twice_area > 0 ? n[a] / twice_area : 0.0;
    const bool junction = s.junction[corners_[3 * t]] || s.junction[corners_[3 * t + 1]] || s.junction[corners_[3 * t + 2]];
    least_[t] = twice_area > 0 ? (junction ? kLeastJunction : kLeast) * twice_area : 1.0;
  }, 1024);
  // Each point's triangles: the corners grouped by point (KEY-REDUCE).
  const auto groups = keyreduce::partition_dense(corners_.data(), static_cast<Id>(corners_.size()),
                                                 static_cast<std::uint32_t>(points), keyreduce::Order::Build);
  std::vector<Id> count(static_cast<std::size_t>(points), 0);
  for (Id g = 0; g < groups.num_groups(); ++g) count[groups.unique_keys[static_cast<std::size_t>(g)]] = groups.count(g);
  offsets_.assign(static_cast<std::size_t>(points + 1), 0);
  for (Id p = 0; p < points; ++p) offsets_[p + 1] = offsets_[p] + count[p];
  triangles_.resize(static_cast<std::size_t>(offsets_[points]));
  parallel::for_each(groups.num_groups(), [&](Id g) {
    const Id p = groups.unique_keys[static_cast<std::size_t>(g)];
    for (Id j = 0; j < groups.count(g); ++j)
      triangles_[offsets_[p] + j] = groups.order[groups.offsets[g] + j] / 3;
  }, 256);
}

bool FoldGuard::keeps(Id p, const double* at, const std::vector<double>& x, const std::vector<double>& candidate) const {
  for (Id j = offsets_[p]; j < offsets_[p + 1]; ++j) {
    const Id t = triangles_[j];
    const std::uint32_t* c = corners_.data() + 3 * t;
    const int k = c[0] == p ? 0 : (c[1] == p ? 1 : 2);
    const Id q = c[(k + 1) % 3], r = c[(k + 2) % 3];
    for (const auto* qs : {&x, &candidate}) {
      const Pair d =
          orientations(at, qs->data() + 3 * q, x.data() + 3 * r, candidate.data() + 3 * r, normal_.data() + 3 * t);
      if (!(d[0] >= least_[t] && d[1] >= least_[t])) return false;
    }
  }
  return true;
}

void FoldGuard::limit(const std::vector<double>& x, const std::vector<double>& candidate,
                      std::vector<double>& out) const {
  parallel::for_each(static_cast<Id>(offsets_.size()) - 1, [&](Id p) {
    const double* from = x.data() + 3 * p;
    const double* to = candidate.data() + 3 * p;
    double at[3] = {from[0], from[1], from[2]};
    if (to[0] != from[0] || to[1] != from[1] || to[2] != from[2]) {
      for (double f : kFractions) {
        for (int a = 0; a < 3; ++a) at[a] = from[a] + f * (to[a] - from[a]);
        if (keeps(p, at, x, candidate)) break;
        for (int a = 0; a < 3; ++a) at[a] = from[a];
      }
    }
    for (int a = 0; a < 3; ++a) out[3 * p + a] = at[a];
  }, 1024);
}

}  // namespace keymesh::generate::detail
