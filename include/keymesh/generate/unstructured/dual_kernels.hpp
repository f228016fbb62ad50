#pragma once
// The dual's per-element work (dual.hpp), shared by its CPU path (dual.cpp)
// and its device path (dual_device.hpp) so that both give the same bits:
// the walk of one point's fans, the rule that makes a fan a polygon, and a
// cell's centroid tuple.
#include <cmath>
#include <cstdint>

#include "keymesh/core/device.hpp"
#include "keymesh/core/types.hpp"

namespace keymesh::generate::dual_kernels {

// The fans of one point (dual.hpp). Its k incident corners, in increasing
// corner order, give links next[i] -> prev[i] (the corner's next and
// previous points in its cell); the fans are the chains of links. Each fan
// is written to `order` (k entries in all: positions 0..k-1 of the corners,
// in walking order) and visit(first, size, open) is called with its span
// order[first, first + size). `used` is k bytes of scratch. Corner lists are
// short (the valence), so the quadratic searches are cheap.
template <class Visit>
KEYMESH_HD void walk_fans(Id k, const PointIndex* next, const PointIndex* prev, std::uint8_t* used,
                          std::uint32_t* order, Visit&& visit) {
  for (Id i = 0; i < k; ++i) used[i] = 0;
  for (Id done = 0; done < k;) {
    // Start a fan where no unused link leads in (an open fan's first cell);
    // otherwise at the first unused corner (a closed fan).
    Id start = -1;
    for (Id i = 0; i < k && start < 0; ++i) {
      if (used[i]) continue;
      const PointIndex a = next[i];
      bool led_into = false;
      for (Id j = 0; j < k && !led_into; ++j) led_into = !used[j] && j != i && prev[j] == a;
      if (!led_into) start = i;
    }
    const bool open = start >= 0;
    if (!open)
      for (Id i = 0; i < k && start < 0; ++i)
        if (!used[i]) start = i;
    const Id first = done;
    for (Id cur = start; cur >= 0;) {
      used[cur] = 1;
      order[done++] = static_cast<std::uint32_t>(cur);
      const PointIndex want = prev[cur];
      Id nxt = -1;
      for (Id j = 0; j < k && nxt < 0; ++j)
        if (!used[j] && next[j] == want) nxt = j;
      cur = nxt;
    }
    visit(first, done - first, open);
  }
}

// A fan becomes a polygon when it has three corners at least, counting the
// point itself for an open fan (which also needs two cells).
KEYMESH_HD inline bool fan_is_polygon(Id size, bool open) {
  return size + (open ? 1 : 0) >= 3 && !(open && size < 2);
}

// The mean of the `components`-tuples of a cell's corners
// conn[b, e), summed in double in corner order; `renormalise` (a 3-component
// "Normals" field) scales a non-zero result to unit length.
template <class Index>
KEYMESH_HD void centroid_tuple(const Index* conn, std::uint64_t b, std::uint64_t e, const float* values,
                               int components, bool renormalise, float* out) {
  const double w = 1.0 / double(e - b);
  for (int x = 0; x < components; ++x) {
    double s = 0;
    for (std::uint64_t k = b; k < e; ++k) s += values[static_cast<std::size_t>(conn[k]) * components + x];
    out[x] = static_cast<float>(s * w);
  }
  if (renormalise) {
    const float l = std::sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
    if (l > 0) out[0] /= l, out[1] /= l, out[2] /= l;
  }
}

}  // namespace keymesh::generate::dual_kernels
