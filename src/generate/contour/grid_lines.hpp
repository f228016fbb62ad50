#pragma once
// Every grid line's coordinate as the float EdgeInterpolator::position()
// rounds it to (contour_kernels.hpp): a point on an edge along `axis` has the
// grid coordinates of the edge's first point but along `axis`, where
// position() adds t, so two of its three floats are looked up here instead
// of computed (the same double expression, hence the same bits, once per
// line instead of once per point). Used by the contour's structured plan,
// fine points (position) and coarse points (a coarse point's crossings
// share its grid coordinates off their axes).
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/generate/contour/contour_kernels.hpp"

namespace keymesh::generate {

// The coordinate along `axis` of the crossing at t on the edge from grid
// index c (slab-local along z) to c + 1: EdgeInterpolator::position()'s
// expression.
[[gnu::always_inline]] inline float grid_coordinate(const GridShape& s, int axis, Id c, double t) {
  const double u = static_cast<double>(c + s.offset[axis]) + t;
  return static_cast<float>(s.origin[axis] + s.spacing[axis] * u);
}

struct GridLines {
  const GridShape& s;
  std::vector<float> line[3];

  explicit GridLines(const GridShape& shape) : s(shape) {
    const Id n[3] = {s.nx, s.ny, s.nz};
    for (int a = 0; a < 3; ++a) {
      line[a].resize(static_cast<std::size_t>(n[a]));
      for (Id c = 0; c < n[a]; ++c)
        line[a][c] = static_cast<float>(s.origin[a] + s.spacing[a] * static_cast<double>(c + s.offset[a]));
    }
  }

  template <class Point>
  [[gnu::always_inline]] void position(const Point& p, float* xyz) const {
    for (int a = 0; a < 3; ++a) xyz[a] = line[a][p.ijk[a]];
    xyz[p.axis] = grid_coordinate(s, p.axis, p.ijk[p.axis], p.t);
  }
};

}  // namespace keymesh::generate
