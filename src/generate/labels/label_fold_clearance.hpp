#pragma once
// The fold guard's clearance (label_fold_clearance.cpp): per triangle and
// iteration, a proof that the guard keeps it on every try (each corner at
// any fraction of its move), by a bound cheaper than the guard's own test,
// so that label_kernels::GuardStep can skip that triangle's tests and give
// the same bits.
#include <cstdint>
#include <vector>

#include "keymesh/core/types.hpp"

namespace keymesh::generate::detail {

// Per triangle t (corners 3 t .. 3 t + 2 into the points), its unsmoothed
// unit normal and least orientation (label_kernels::GuardFrame), and the
// iteration's present positions x and candidate positions (3 per point).
struct ClearanceInput {
  const std::uint32_t* corners;
  const double* normal;
  const double* least;
  const double* x;
  const double* candidate;
  Id points, triangles;
};

class FoldClearance {
 public:
  // Sets clear()[t] to 1 where every orientation GuardStep computes for
  // triangle t on any try (each moving corner at 1, 1/2, 1/4 or 1/8 of its
  // move, the two others at either end of theirs) is proven >= least[t]; 0
  // where not proven (GuardStep then tests it). Sound for any finite input.
  void update(const ClearanceInput& in);
  const std::uint8_t* clear() const { return clear_.data(); }
  // Per point: 1 where clear() holds for every triangle of the point.
  const std::uint8_t* clear_point() const { return clear_point_.data(); }

  // Per point and iteration: its move candidate - x and the move's length,
  // one record so that a triangle's corner costs one cache line.
  struct alignas(32) Move {
    double d[3];
    double reach;
  };

 private:
  std::vector<Move> move_;                 // per point
  std::vector<std::uint8_t> clear_;        // per triangle
  std::vector<std::uint8_t> clear_point_;  // per point
};

// The bound for one triangle (exposed for its test): its corners' present
// and candidate positions, their moves' lengths |to - from|, its normal and
// least orientation, and the rounding slack for coordinates of magnitude at
// most `size` (clearance_slack).
bool triangle_clear(const double* const from[3], const double* const to[3], const double reach[3], const double* normal,
                    double least, double slack);
double clearance_slack(double size);

}  // namespace keymesh::generate::detail
