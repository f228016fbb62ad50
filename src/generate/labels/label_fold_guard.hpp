#pragma once
// The fold guard of label smoothing (label_fold_guard.cpp): every step may
// move a point only as far as keeps each of its triangles turned the way it
// faced unsmoothed, whatever its neighbours do in the same step.
#include <cstdint>
#include <vector>

#include "keymesh/core/array.hpp"

#include "label_fold_clearance.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

class FoldGuard {
 public:
  // Reference normals from the surface's present (unsmoothed) positions, and
  // each point's corners.
  explicit FoldGuard(const LabelSurface& surface);

  // out = x + f (candidate - x) per point, f the largest of 1, 1/2, 1/4,
  // 1/8 for which every triangle of the point keeps its orientation
  // (label_kernels::GuardStep), else 0 (the point stays).
  void limit(const std::vector<double>& x, const std::vector<double>& candidate, std::vector<double>& out);

  // The moves limit() has shortened or refused so far, over every point.
  Id shortened() const;

 private:
  const Array<PointIndex>& corners_;  // the mesh's connectivity, 3 per triangle
  std::vector<Id> offsets_;           // per point, into point_corners_
  std::vector<std::uint32_t> point_corners_;  // each point's corners (3 t + k)
  std::vector<double> normal_;                // per triangle: its unsmoothed unit normal
  std::vector<double> least_;                 // per triangle: the least orientation allowed
  std::vector<std::uint32_t> shortened_;      // per point: its moves shortened or refused
  FoldClearance clearance_;                   // per iteration: the triangles proven to keep
};

}  // namespace keymesh::generate::detail
