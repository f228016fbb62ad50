#pragma once
// Which of a short list of point ids equal a given one, as a bit mask: the
// way a point's fan is read without sorting its corners (a sort per point,
// on lists of six to twelve ids, costs more than everything else done
// there: its branches are a coin toss).
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "keymesh/core/types.hpp"

namespace keymesh {

// Bit k set when ids[k] == w, for k < n rounded up to a multiple of 4: the
// caller pads ids[n .. n rounded up) with an id that never matches (or masks
// those bits off). n <= 64.
inline std::uint64_t equal_mask(const PointIndex* ids, Id n, PointIndex w) {
  std::uint64_t m = 0;
#if defined(__SSE2__)
  const __m128i wide = _mm_set1_epi32(static_cast<int>(w));
  for (Id k = 0; k < n; k += 4) {
    const __m128i four = _mm_loadu_si128(reinterpret_cast<const __m128i*>(ids + k));
    m |= std::uint64_t{static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(four, wide))))} << k;
  }
#else
  for (Id k = 0; k < (n + 3) / 4 * 4; ++k) m |= std::uint64_t{ids[k] == w} << k;
#endif
  return m;
}

}  // namespace keymesh
