#pragma once
// history_t (ContourOptions::history, docs/HISTORY.md): the float32 a user
// stores per point to find it again on its edge. The crossing's own t is a
// double; its nearest float may move the recomputed coordinate by a float
// step, so the float written is the one nearest t among those that give the
// written coordinate back through the documented formula
//   x[axis] = float(origin[axis] + spacing[axis] * (double(c) + double(t)))
// (grid_coordinate, the expression positions are written with). Where no
// float within kHistorySteps steps of t does (a coordinate finer than
// spacing * 2^-24: an edge that crosses the coordinate's zero), t's nearest
// float is written, and the recomputed coordinate is within
// |spacing| * 2^-25 + one float step of the written one (t rounds by at most
// 2^-25 in [0, 1]; the float rounding of the two coordinates adds the step).
#include <cmath>

#include "grid_lines.hpp"

namespace keymesh::generate {

inline constexpr int kHistorySteps = 8;

// The float in [0, 1] nearest t, within kHistorySteps float steps of it,
// for which gives_back(float) holds; t's nearest float when none does.
template <class GivesBack>
float nearest_float_t(double t, const GivesBack& gives_back_at) {
  const float nearest = static_cast<float>(t);
  auto gives_back = [&](float f) { return f >= 0.f && f <= 1.f && gives_back_at(f); };
  if (gives_back(nearest)) return nearest;
  float below = nearest, above = nearest;
  for (int step = 0; step < kHistorySteps; ++step) {
    below = std::nextafter(below, -1.f);
    above = std::nextafter(above, 2.f);
    // The nearer of the two to t first (both at the same step count).
    const bool below_first = t - static_cast<double>(below) <= static_cast<double>(above) - t;
    if (gives_back(below_first ? below : above)) return below_first ? below : above;
    if (gives_back(below_first ? above : below)) return below_first ? above : below;
  }
  return nearest;
}

// The history_t of the crossing at t on the edge from grid index c (slab
// local, as grid_coordinate takes it) along `axis`.
inline float history_t(const GridShape& s, int axis, Id c, double t) {
  const float written = grid_coordinate(s, axis, c, t);
  return nearest_float_t(t, [&](float f) { return grid_coordinate(s, axis, c, f) == written; });
}

}  // namespace keymesh::generate
