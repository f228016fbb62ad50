#include "keymesh/generate/coarsen/split_nonmanifold.hpp"

#include <algorithm>
#include <bit>
#include <atomic>
#include <functional>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "keymesh/core/error.hpp"
#include "keymesh/core/uninitialized_array.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"
#include "keymesh/parallel/scan.hpp"
#include "split_fans.hpp"

namespace keymesh::generate {

namespace {

using split_rule::CornerEnds;
using split_rule::FanRule;
using split_rule::half_edges;

// The corners after and before corner c in its triangle: at c's point, the
// point there is the end of the edge leaving it and the start of the edge
// arriving at it.
std::uint32_t next_corner(std::uint32_t c) { return c % 3 == 2 ? c - 2 : c + 1; }
std::uint32_t prev_corner(std::uint32_t c) { return c % 3 == 0 ? c + 2 : c - 1; }

// The spokes of a corner of point v: the point its triangle's edge leaving
// v ends at, and the point the edge arriving at v starts from.
struct Spokes {
  PointIndex next, prev;
};

// The arriving edges of eight corners' spokes, for finding which start at a
// point: straight from the spokes (four loads, two shuffles where SSE2 is
// there; copying them out first stalled on every point, the wide load
// waiting for the narrow stores).
struct EightPrev {
#if defined(__SSE2__)
  __m128 lo, hi;
  explicit EightPrev(const Spokes* s) {
    auto two = [&](int k) { return _mm_loadu_ps(reinterpret_cast<const float*>(s + k)); };
    lo = _mm_shuffle_ps(two(0), two(2), _MM_SHUFFLE(3, 1, 3, 1));
    hi = _mm_shuffle_ps(two(4), two(6), _MM_SHUFFLE(3, 1, 3, 1));
  }
  // Bit k set when corner k's arriving edge starts at w.
  unsigned starting_at(PointIndex w) const {
    const __m128i wide = _mm_set1_epi32(static_cast<int>(w));
    auto mask = [&](__m128 four) {
      return static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(_mm_castps_si128(four), wide))));
    };
    return mask(lo) | mask(hi) << 4;
  }
#else
  PointIndex prev[8];
  explicit EightPrev(const Spokes* s) {
    for (int k = 0; k < 8; ++k) prev[k] = s[k].prev;
  }
  unsigned starting_at(PointIndex w) const {
    unsigned m = 0;
    for (unsigned k = 0; k < 8; ++k) m |= unsigned{prev[k] == w} << k;
    return m;
  }
#endif
};

// The common point, checked without building its fans: from each corner
// the leaving edge's end w leads to the one corner whose arriving edge
// starts at w; v is one closed fan when that is a single cycle through all
// d corners. No w may be v, and each w must start exactly one arriving
// edge (a second corner with the same arriving edge is another fan, or a
// non-manifold edge). The order of the corners does not matter. Anything
// else goes to FanRule.
// Up to kSmall corners (nearly every point) the corner w leads to is found
// by comparing w with all kSmall arriving edges at once, without a branch
// on where it is (a coin toss that mispredicted at every step).
constexpr Id kSpokesRead = 8;

bool one_closed_fan(PointIndex v, const Spokes* s, Id d) {
  constexpr Id kSmall = kSpokesRead;
  if (d < 3) return false;
  if (d <= kSmall) {
    const EightPrev prev(s);  // reads s[0, 8): the callers' arrays have room
    const unsigned corners = (1u << d) - 1;
    std::uint8_t to[kSmall] = {};
    bool bad = false;
    for (Id j = 0; j < d; ++j) {
      const PointIndex w = s[j].next;
      const unsigned match = prev.starting_at(w) & corners;
      bad |= (w == v) | (std::popcount(match) != 1);
      to[j] = static_cast<std::uint8_t>(std::countr_zero(match | 0x100u));
    }
    if (bad) return false;
    Id j = to[0], steps = 1;
    while (j != 0 && steps < d) j = to[j], ++steps;
    return j == 0 && steps == d;
  }
  Id j = 0, steps = 0;
  do {
    const PointIndex w = s[j].next;
    if (w == v) return false;
    Id i = 0;
    while (i < d && s[i].prev != w) ++i;
    if (i == d) return false;
    for (Id other = i + 1; other < d; ++other)
      if (s[other].prev == w) return false;
    j = i;
  } while (++steps < d && j != 0);
  return j == 0 && steps == d;
}

// The same for corners given by index (the few points looked at again).
bool one_closed_fan(const PointIndex* C, PointIndex v, const std::uint32_t* list, Id d) {
  constexpr Id kOnStack = 64;
  Spokes on_stack[kOnStack];
  std::vector<Spokes> on_heap;
  if (d + kSpokesRead > kOnStack) on_heap.resize(static_cast<std::size_t>(d + kSpokesRead));
  Spokes* s = on_heap.empty() ? on_stack : on_heap.data();
  for (Id j = 0; j < d; ++j) s[j] = {C[next_corner(list[j])], C[prev_corner(list[j])]};
  for (Id j = d; j < d + kSpokesRead; ++j) s[j] = {};  // read, never matched
  return one_closed_fan(v, s, d);
}

// The points the rule looks at, by increasing id, with their corners
// (increasing): those that are not one closed fan (and, told suspects, the
// few suspects that are).
struct Flagged {
  std::vector<PointIndex> point;
  std::vector<std::uint32_t> first{0};  // point k's corners: corners[first[k] .. first[k + 1])
  std::vector<std::uint32_t> corners;

  // The ends of each corner's leaving and arriving edges (read_ends), as
  // the rule reads them: the ids the triangles hold when read.
  std::vector<PointIndex> to, from;

  std::size_t size() const { return point.size(); }
  const std::uint32_t* list(std::size_t k) const { return corners.data() + first[k]; }
  Id degree(std::size_t k) const { return first[k + 1] - first[k]; }
  CornerEnds ends(std::size_t k) const { return {to.data() + first[k], from.data() + first[k], degree(k)}; }
  void read_ends(const PointIndex* C) {
    to.assign(corners.size() + split_rule::kEndsReadPast, 0);
    from.assign(corners.size() + split_rule::kEndsReadPast, 0);
    for (std::size_t i = 0; i < corners.size(); ++i) to[i] = C[next_corner(corners[i])], from[i] = C[prev_corner(corners[i])];
  }
  std::size_t at(PointIndex p) const {
    return static_cast<std::size_t>(std::lower_bound(point.begin(), point.end(), p) - point.begin());
  }
  void add(PointIndex p, const std::uint32_t* list, Id d) {
    point.push_back(p);
    corners.insert(corners.end(), list, list + d);
    first.push_back(static_cast<std::uint32_t>(corners.size()));
  }
};

// Every point's spokes, grouped by point: a counting sort, counted then
// placed, the order within a point left to the threads (one_closed_fan does
// not depend on it). Stored as spokes rather than corner ids, so that the
// check reads one contiguous run per point instead of gathering from the
// triangles.
// Without atomics where the triangles come in the order of their points, as
// a contour's do (a voxel row's triangles use the points of two grid rows of
// two planes): each chunk of triangles owns the points from its smallest to
// the next chunk's smallest and counts and places its corners there with
// plain stores, before the others; the corners it holds of other chunks'
// points (a contour's: those of its last plane) are counted and placed
// after, with atomics. Triangles in any other order are grouped the same,
// only with more atomics.
// Kept by the calling thread between calls (a session splitting one mesh
// after another reuses mapped pages instead of faulting in fresh ones),
// unless past kKeepScratchBytes.
struct CornersByPoint {
  std::uint32_t* end;  // point p's spokes: [p ? end[p - 1] : 0, end[p])
  Spokes* spokes;      // kSpokesRead more than the corners: one_closed_fan reads 8 at once

  struct Scratch {
    KeptArray<std::uint32_t> end;
    KeptArray<Spokes> spokes;
  };
  static Scratch& scratch() {
    thread_local Scratch kept;
    return kept;
  }
  ~CornersByPoint() {
    Scratch& s = scratch();
    if (s.end.size * sizeof(std::uint32_t) + s.spokes.size * sizeof(Spokes) > kKeepScratchBytes) s = {};
  }

  CornersByPoint(const PointIndex* C, Id corners, Id n)
      : end(scratch().end.room_for(static_cast<std::size_t>(n + 1))),
        spokes(scratch().spokes.room_for(static_cast<std::size_t>(corners) + kSpokesRead)) {
    const Id triangles = corners / 3;
    const int chunks = parallel::chunk_count(triangles, 1 << 14);
    std::vector<PointIndex> owned(static_cast<std::size_t>(chunks) + 1);  // chunk c's: [owned[c], owned[c + 1])
    parallel::for_each_chunk(triangles, chunks, [&](Id b, Id e, int c) {
      owned[c] = b < e ? *std::min_element(C + 3 * b, C + 3 * e) : static_cast<PointIndex>(n);
    });
    owned[0] = 0;
    for (int c = 1; c < chunks; ++c) owned[c] = std::max(owned[c], owned[c - 1]);
    owned[chunks] = static_cast<PointIndex>(n);
    std::fill(spokes + corners, spokes + corners + kSpokesRead, Spokes{0, 0});
    std::uint32_t* count = end;
    count[n] = 0;
    std::vector<std::vector<std::uint32_t>> spilled(static_cast<std::size_t>(chunks));
    parallel::for_each_chunk(triangles, chunks, [&](Id b, Id e, int c) {
      const PointIndex lo = owned[c], hi = owned[c + 1];
      std::fill(count + lo, count + hi, 0u);
      for (Id x = 3 * b; x < 3 * e; ++x) {
        const PointIndex p = C[x];
        if (p - lo < hi - lo)  // lo <= p < hi
          ++count[p];
        else
          spilled[c].push_back(static_cast<std::uint32_t>(x));
      }
    });
    // A point id past the last point can only be among the spilled corners
    // (the owned ranges end at n): refused before any is counted.
    for (const auto& list : spilled)
      for (std::uint32_t x : list)
        if (C[x] >= n)
          throw InputError("split_nonmanifold: corner " + std::to_string(x) + " refers to point " +
                           std::to_string(C[x]) + " of " + std::to_string(n));
    auto spilled_corners = [&](auto&& f) {
      parallel::for_each_chunk(chunks, chunks, [&](Id c, Id, int) {
        for (std::uint32_t x : spilled[c]) f(x, std::atomic_ref<std::uint32_t>(count[C[x]]));
      });
    };
    spilled_corners([](std::uint32_t, std::atomic_ref<std::uint32_t> n_p) { n_p.fetch_add(1, std::memory_order_relaxed); });
    parallel::exclusive_scan(count, count, n + 1);  // each point's first slot, then (placed) its end
    parallel::for_each_chunk(triangles, chunks, [&](Id b, Id e, int c) {
      const PointIndex lo = owned[c], hi = owned[c + 1];
      for (Id t = b; t < e; ++t) {
        const PointIndex* x = C + 3 * t;
        for (int k = 0; k < 3; ++k) {
          const PointIndex p = x[k];
          if (p - lo < hi - lo) spokes[count[p]++] = {x[k == 2 ? 0 : k + 1], x[k == 0 ? 2 : k - 1]};
        }
      }
    });
    spilled_corners([&](std::uint32_t x, std::atomic_ref<std::uint32_t> slot) {
      spokes[slot.fetch_add(1, std::memory_order_relaxed)] = {C[next_corner(x)], C[prev_corner(x)]};
    });
  }

  Id begin(Id p) const { return p == 0 ? 0 : end[p - 1]; }
};

// The corners of `points` (ascending), gathered in one pass over the
// triangles, by point and increasing corner: the few the rule looks at, in
// an order that makes all after this deterministic (points without a
// corner there left out).
// Grouped by counting: each listed point's rank among them comes from a bit
// per point and the listed points before each 64-point word, and the
// corners are found in increasing order, so that placing them in that order
// keeps them increasing within each point (a sort of them cost more than
// the pass over the triangles).
Flagged corners_of(const PointIndex* C, Id n, const std::vector<PointIndex>& points,
                   const std::vector<TriangleRange>& where) {
  if (points.empty()) return {};
  const auto words = static_cast<std::size_t>(n / 64 + 1);
  std::vector<std::uint64_t> is_listed(words, 0);
  for (PointIndex p : points) is_listed[p / 64] |= std::uint64_t{1} << (p % 64);
  std::vector<std::uint32_t> rank_before(words);
  std::vector<PointIndex> listed_points;  // by rank (a point listed twice once)
  for (std::size_t w = 0; w < words; ++w) {
    rank_before[w] = static_cast<std::uint32_t>(listed_points.size());
    for (std::uint64_t m = is_listed[w]; m; m &= m - 1)
      listed_points.push_back(static_cast<PointIndex>(64 * w + static_cast<std::size_t>(std::countr_zero(m))));
  }
  // The ranges cut into pieces of about 2^15 triangles, the pieces shared
  // among the threads (each chunk's in increasing order).
  std::vector<TriangleRange> pieces;
  for (const TriangleRange& r : where)
    for (Id b = r.begin; b < r.end; b += Id{1} << 15) pieces.push_back({b, std::min(r.end, b + (Id{1} << 15))});
  const int chunks = parallel::chunk_count(static_cast<Id>(pieces.size()), 1);
  std::vector<std::vector<std::uint64_t>> at(static_cast<std::size_t>(std::max(chunks, 1)));  // rank << 32 | corner
  std::vector<std::uint8_t> past_last(at.size(), 0);
  const std::uint64_t* listed = is_listed.data();
  // The scan tests a byte per point (three loads a triangle; the bits took
  // a shift and a mask more each), kept zero between calls by the calling
  // thread (set for the listed points, cleared after).
  thread_local std::vector<std::uint8_t> listed_bytes;
  if (listed_bytes.size() < static_cast<std::size_t>(n)) listed_bytes.resize(static_cast<std::size_t>(n));
  for (PointIndex p : listed_points) listed_bytes[p] = 1;
  const std::uint8_t* is = listed_bytes.data();
  parallel::for_each_chunk(static_cast<Id>(pieces.size()), chunks, [&](Id piece_begin, Id piece_end, int chunk) {
    for (Id piece = piece_begin; piece < piece_end; ++piece) {
      const Id begin = pieces[piece].begin, end = pieces[piece].end;
      // Every id below n before any is looked up (one pass the compiler
      // vectorises, not a test a triangle).
      PointIndex most = 0;
      for (Id x = 3 * begin; x < 3 * end; ++x) most = std::max(most, C[x]);
      if (most >= n) {
        past_last[chunk] = 1;
        return;
      }
      // A triangle at a time: one test for its three corners (nearly every
      // triangle has none of the few listed points).
      for (Id t = begin; t < end; ++t) {
        const PointIndex* x = C + 3 * t;
        if (is[x[0]] | is[x[1]] | is[x[2]])
          for (int k = 0; k < 3; ++k)
            if (is[x[k]]) {
              const PointIndex p = x[k];
              const std::uint64_t below = listed[p / 64] & ((std::uint64_t{1} << (p % 64)) - 1);
              const std::uint64_t rank = rank_before[p / 64] + static_cast<std::uint64_t>(std::popcount(below));
              at[chunk].push_back(rank << 32 | static_cast<std::uint64_t>(3 * t + k));
            }
      }
    }
  });
  for (PointIndex p : listed_points) listed_bytes[p] = 0;
  if (listed_bytes.size() > kKeepScratchBytes) listed_bytes = {};
  if (std::find(past_last.begin(), past_last.end(), 1) != past_last.end())
    throw InputError("split_nonmanifold: a corner refers to a point past the last");
  std::vector<std::uint32_t> first(listed_points.size() + 1, 0);
  for (const auto& a : at)
    for (std::uint64_t e : a) ++first[(e >> 32) + 1];
  for (std::size_t k = 0; k < listed_points.size(); ++k) first[k + 1] += first[k];
  std::vector<std::uint32_t> corners(first.back());
  {
    std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
    for (const auto& a : at)
      for (std::uint64_t e : a) corners[next[e >> 32]++] = static_cast<std::uint32_t>(e);
  }
  // The grouped corners become the list as they are (a point without a
  // corner there has an empty run: left out).
  Flagged out;
  out.corners = std::move(corners);
  for (std::size_t k = 0; k < listed_points.size(); ++k)
    if (first[k + 1] > first[k]) out.point.push_back(listed_points[k]), out.first.push_back(first[k + 1]);
  return out;
}

// The points that are not one closed fan (one_closed_fan over their
// spokes), with their corners (corners_of). `unused` gets the points
// without a corner, ascending.
Flagged flag_points(const PointIndex* C, Id corners, Id n, std::vector<PointIndex>& unused) {
  std::vector<PointIndex> odd;
  {
    const CornersByPoint by_point(C, corners, n);
    const int chunks = parallel::chunk_count(n, 1 << 14);
    std::vector<std::vector<PointIndex>> found(static_cast<std::size_t>(std::max(chunks, 1))), lone(found.size());
    parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int chunk) {
      for (Id p = b; p < e; ++p) {
        const Id first = by_point.begin(p), d = by_point.end[p] - first;
        if (d == 0)
          lone[chunk].push_back(static_cast<PointIndex>(p));
        else if (!one_closed_fan(static_cast<PointIndex>(p), by_point.spokes + first, d))
          found[chunk].push_back(static_cast<PointIndex>(p));
      }
    });
    for (const auto& points : found) odd.insert(odd.end(), points.begin(), points.end());
    for (const auto& points : lone) unused.insert(unused.end(), points.begin(), points.end());
  }
  return corners_of(C, n, odd, {{0, corners / 3}});
}

// The groups of corners that `regrouped` lists, those still not one closed
// fan under the ids the corners hold now.
// The groups are shared among the threads, each chunk's odd ones listed in
// order.
Flagged still_odd(const PointIndex* C, const Flagged& regrouped) {
  const int chunks = parallel::chunk_count(static_cast<Id>(regrouped.size()), 1024);
  std::vector<std::vector<std::uint32_t>> odd(static_cast<std::size_t>(std::max(chunks, 1)));
  parallel::for_each_chunk(static_cast<Id>(regrouped.size()), chunks, [&](Id b, Id e, int c) {
    for (Id k = b; k < e; ++k)
      if (!one_closed_fan(C, regrouped.point[k], regrouped.list(k), regrouped.degree(k)))
        odd[c].push_back(static_cast<std::uint32_t>(k));
  });
  Flagged out;
  for (const auto& groups : odd)
    for (std::uint32_t k : groups) out.add(regrouped.point[k], regrouped.list(k), regrouped.degree(k));
  return out;
}

// Every flagged point's fans under the current rotations, recomputed for
// the two ends of an edge whose rotation changes. The first time, the
// points are shared among the threads (each point's fans are its own).
struct FanCache {
  const FanRule& fans;
  const Flagged& f;
  std::vector<std::uint32_t> labels_;  // point k's from f.first[k], like its corners

  FanCache(const FanRule& rule, const Flagged& flagged, std::vector<std::uint64_t>& found)
      : fans(rule), f(flagged), labels_(flagged.corners.size()) {
    const int chunks = parallel::chunk_count(static_cast<Id>(f.size()), 512);
    std::vector<std::vector<std::uint64_t>> found_by(static_cast<std::size_t>(std::max(chunks, 1)));
    parallel::for_each_chunk(static_cast<Id>(f.size()), chunks, [&](Id b, Id e, int c) {
      for (Id k = b; k < e; ++k) fans(f.point[k], f.ends(k), labels(k), &found_by[c]);
    });
    for (const auto& keys : found_by) found.insert(found.end(), keys.begin(), keys.end());
  }
  std::uint32_t* labels(std::size_t k) { return labels_.data() + f.first[k]; }
  void refresh(std::size_t k) { fans(f.point[k], f.ends(k), labels(k), nullptr); }
};

// The edges with two pairs or more (`multi`, by key) as the sweeps read
// them: their ends' places among the flagged points, and the triangles
// running up each (lo's corners leaving for hi and hi's arriving from lo:
// the same triangles in the same order), found once a round.
struct MultiEdges {
  std::vector<std::uint32_t> lo, hi;     // by edge: its ends' flagged indices
  std::vector<std::uint32_t> first{0};   // edge e's triangles up: [first[e], first[e + 1])
  std::vector<std::uint32_t> at_lo, at_hi;

  MultiEdges(const Flagged& f, const std::vector<std::uint64_t>& multi) {
    std::vector<std::uint32_t> up;
    for (std::uint64_t key : multi) {
      const PointIndex p = static_cast<PointIndex>(key >> 32), q = static_cast<PointIndex>(key & 0xffffffffu);
      const std::size_t a = f.at(p), b = f.at(q);
      lo.push_back(static_cast<std::uint32_t>(a)), hi.push_back(static_cast<std::uint32_t>(b));
      half_edges(f.ends(a).to, f.degree(a), q, up);
      at_lo.insert(at_lo.end(), up.begin(), up.end());
      half_edges(f.ends(b).from, f.degree(b), p, up);
      at_hi.insert(at_hi.end(), up.begin(), up.end());
      first.push_back(static_cast<std::uint32_t>(at_lo.size()));
    }
  }
  std::uint32_t pairs(std::size_t e) const { return first[e + 1] - first[e]; }

  // Whether edge e's pairs join the same fan at both ends twice.
  bool joins_twice(FanCache& cache, std::size_t e) {
    const std::uint32_t *fans_lo = cache.labels(lo[e]), *fans_hi = cache.labels(hi[e]);
    ends.clear();
    for (std::uint32_t i = first[e]; i < first[e + 1]; ++i)
      ends.push_back((std::uint64_t{fans_lo[at_lo[i]]} << 32) | fans_hi[at_hi[i]]);
    std::sort(ends.begin(), ends.end());
    return std::adjacent_find(ends.begin(), ends.end()) != ends.end();
  }

 private:
  std::vector<std::uint64_t> ends;
};

// Sweeps over the multi-edges in key order: a conflicted edge takes the
// first rotation that separates its pairs.
void rotate_pairings(FanCache& cache, MultiEdges& edges, std::vector<std::uint32_t>& rotation) {
  auto refresh = [&](std::size_t e) { cache.refresh(edges.lo[e]), cache.refresh(edges.hi[e]); };
  for (int sweep = 0; sweep < 4; ++sweep) {
    bool changed = false;
    for (std::size_t e = 0; e < rotation.size(); ++e) {
      if (!edges.joins_twice(cache, e)) continue;
      const std::uint32_t pairs = edges.pairs(e), was = rotation[e];
      for (std::uint32_t r = 1; r < pairs; ++r) {
        rotation[e] = (was + r) % pairs;
        refresh(e);
        if (!edges.joins_twice(cache, e)) break;
        rotation[e] = was;
        refresh(e);
      }
      changed = changed || rotation[e] != was;
    }
    if (!changed) break;
  }
}

// The edges left joined after the sweeps: all of them, and those whose
// smaller end's original (a copy's is the point it copies) `counts` names.
struct EdgesLeft {
  Id all = 0, counted = 0;
};
EdgesLeft edges_left(FanCache& cache, MultiEdges& edges, const Flagged& f, Id n, const std::vector<PointIndex>& source,
                     const std::function<bool(PointIndex)>* counts) {
  EdgesLeft left;
  for (std::size_t e = 0; e < edges.lo.size(); ++e) {
    if (!edges.joins_twice(cache, e)) continue;
    ++left.all;
    const PointIndex lo = f.point[edges.lo[e]];
    if (counts && (*counts)(Id{lo} < n ? lo : source[lo - n])) ++left.counted;
  }
  return left;
}

// One pass of the rule over the flagged points: the pairings rotated, then
// every fan but a point's first given a new id (appended to `source`: the
// original point it copies). All is decided before a corner is rewritten,
// since the rule reads the other points' ids. Returns the edges left joined
// (`counts`: see EdgesLeft); `split_from` gets the point each copy's fan left;
// `regrouped` gets the flagged corners grouped by the ids they hold after
// (ascending ids: the points kept their first fans, in order, and the
// copies' ids come after every id there was).
EdgesLeft split_round(PointIndex* C, Id n, Flagged& f, std::vector<PointIndex>& source,
                      std::vector<PointIndex>& split_from, Flagged& regrouped,
                      const std::function<bool(PointIndex)>* counts) {
  std::vector<std::uint64_t> multi;
  std::vector<std::uint32_t> rotation;
  const FanRule fans{multi, rotation};
  f.read_ends(C);
  FanCache cache(fans, f, multi);
  std::sort(multi.begin(), multi.end());
  // Both ends of such an edge are flagged when every point that is not one
  // closed fan is (a caller's list of suspects may lack one: its edges are
  // then left as they are rather than looked up where they are not).
  auto flagged = [&](PointIndex p) { return std::binary_search(f.point.begin(), f.point.end(), p); };
  std::erase_if(multi, [&](std::uint64_t key) {
    return !flagged(static_cast<PointIndex>(key >> 32)) || !flagged(static_cast<PointIndex>(key & 0xffffffffu));
  });
  rotation.assign(multi.size(), 0);
  MultiEdges edges(f, multi);
  rotate_pairings(cache, edges, rotation);
  const EdgesLeft left = edges_left(cache, edges, f, n, source, counts);
  std::vector<std::pair<std::uint32_t, PointIndex>> moves;  // corner, new id
  std::vector<PointIndex> id_of_root;
  Flagged copies;
  regrouped = {};
  std::vector<std::uint32_t> group;
  for (std::size_t k = 0; k < f.size(); ++k) {
    const std::uint32_t* labels = cache.labels(k);
    const auto d = static_cast<std::size_t>(f.degree(k));
    id_of_root.assign(d, f.point[k]);
    const PointIndex original = Id{f.point[k]} < n ? f.point[k] : source[f.point[k] - n];
    for (std::size_t r = 0; r < d; ++r) {
      if (labels[r] != r) continue;
      if (r > 0) {
        if (n + static_cast<Id>(source.size()) >= Id{std::numeric_limits<PointIndex>::max()})
          throw LimitError("split_nonmanifold: more than 2^32 - 1 points");
        id_of_root[r] = static_cast<PointIndex>(n + static_cast<Id>(source.size()));
        source.push_back(original);
        split_from.push_back(f.point[k]);
      }
      group.clear();
      for (std::size_t j = r; j < d; ++j)
        if (labels[j] == r) group.push_back(f.list(k)[j]);
      (r ? copies : regrouped).add(id_of_root[r], group.data(), static_cast<Id>(group.size()));
    }
    for (std::size_t j = 1; j < d; ++j)
      if (labels[j] != 0) moves.emplace_back(f.list(k)[j], id_of_root[labels[j]]);
  }
  for (const auto& [corner, id] : moves) C[corner] = id;
  for (std::size_t k = 0; k < copies.size(); ++k) regrouped.add(copies.point[k], copies.list(k), copies.degree(k));
  return left;
}

}  // namespace

namespace {

// The rule over the flagged points, then the copies appended. `rounds`
// (parts of one mesh): the rounds agreed with the other parts.
void split_flagged(SurfaceMesh& mesh, Flagged f, NonmanifoldSplit& result, const SplitRounds* rounds = nullptr) {
  const Id n = mesh.num_points();
  PointIndex* C = mesh.connectivity.data();
  std::vector<PointIndex> source;  // the original point each new id copies
  result.first_flagged = f.point;
  // A split renames the corners around the points it splits, which can let
  // a rotation separate an edge it could not before: the points still
  // flagged are looked at again (a few rounds, each over them only).
  for (int round = 0; round < 4 && (rounds || f.size() > 0); ++round) {
    const std::size_t added_before = source.size();
    Flagged regrouped;
    const EdgesLeft left =
        split_round(C, n, f, source, result.split_from, regrouped, rounds ? &rounds->counts : nullptr);
    result.copy_round.resize(source.size(), static_cast<std::uint8_t>(round + 1));
    result.rounds = round + 1;
    result.edges_left = rounds ? left.counted : left.all;
    Id counted_added = 0;
    for (std::size_t i = added_before; rounds && i < source.size(); ++i) counted_added += rounds->counts(source[i]);
    const bool again = rounds ? rounds->go_on(counted_added, left.counted)
                              : source.size() != added_before && left.all != 0;
    if (!again) break;
    f = still_odd(C, regrouped);
  }
  const Id added = static_cast<Id>(source.size());
  // In the room the caller left after the points (the contour's pass), or
  // in arrays grown to their exact size (resize() past the capacity would
  // double it).
  auto append_copies = [&](Array<float>& values, int k) {
    const auto size = static_cast<std::size_t>((n + added) * k);
    if (values.capacity() < size) {
      Array<float> grown;
      parallel::reserve_fresh(grown, size);
      grown.resize(static_cast<std::size_t>(n * k));
      parallel::for_each(n * k, [&](Id i) { grown[i] = values[i]; }, 1 << 16);
      values.swap(grown);
    }
    values.resize(size);  // within the capacity, unwritten (Array)
    for (Id i = 0; i < added; ++i) std::copy_n(values.begin() + Id{source[i]} * k, k, values.begin() + (n + i) * k);
  };
  if (added > 0) {
    append_copies(mesh.points, 3);
    for (Field& field : mesh.point_fields) append_copies(field.values, field.components);
  }
  result.points_added = added;
}

// Refuses what the rule cannot take; the corner count.
Id checked_corners(const SurfaceMesh& mesh) {
  if (!mesh.all_triangles()) throw InputError("split_nonmanifold: the mesh has polygons; only triangles are split");
  const Id corners = static_cast<Id>(mesh.connectivity.size());
  if (corners > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("split_nonmanifold: more than 2^32 - 1 corners");
  return corners;
}

}  // namespace

NonmanifoldSplit split_nonmanifold(SurfaceMesh& mesh) {
  const Id corners = checked_corners(mesh), n = mesh.num_points();
  NonmanifoldSplit result;
  if (corners == 0) {
    result.unused.resize(static_cast<std::size_t>(n));
    for (Id p = 0; p < n; ++p) result.unused[p] = static_cast<PointIndex>(p);
    return result;
  }
  Flagged f = flag_points(mesh.connectivity.data(), corners, n, result.unused);
  split_flagged(mesh, std::move(f), result);
  return result;
}

NonmanifoldSplit split_nonmanifold(SurfaceMesh& mesh, const NonmanifoldSuspects& suspects) {
  const Id corners = checked_corners(mesh), n = mesh.num_points();
  const std::vector<PointIndex>& points = suspects.points;
  if (!std::is_sorted(points.begin(), points.end()) || (!points.empty() && Id{points.back()} >= n))
    throw InputError("split_nonmanifold: the suspects must be ascending ids of the mesh's points");
  std::vector<TriangleRange> where = suspects.triangles;
  if (where.empty()) where.push_back({0, corners / 3});
  for (std::size_t r = 0; r < where.size(); ++r)
    if (where[r].begin < (r ? where[r - 1].end : 0) || where[r].end < where[r].begin || where[r].end > corners / 3)
      throw InputError("split_nonmanifold: the suspects' triangle ranges must be ascending, disjoint ranges of the mesh's");
  NonmanifoldSplit result;
  // A suspect that is one closed fan after all is not checked again: the
  // rule gives it one fan, and finds no edge of it with two pairs (each of
  // its neighbours is left once and arrived from once), so it changes
  // nothing (the check cost more than the rule on the few such points).
  split_flagged(mesh, corners_of(mesh.connectivity.data(), n, points, where), result);
  return result;
}

NonmanifoldSplit split_nonmanifold_part(SurfaceMesh& mesh, const SplitRounds& rounds) {
  const Id corners = checked_corners(mesh), n = mesh.num_points();
  NonmanifoldSplit result;
  // A part without a triangle still takes part in every round's agreement.
  Flagged f;
  if (corners == 0)
    for (Id p = 0; p < n; ++p) result.unused.push_back(static_cast<PointIndex>(p));
  else
    f = flag_points(mesh.connectivity.data(), corners, n, result.unused);
  split_flagged(mesh, std::move(f), result, &rounds);
  return result;
}

}  // namespace keymesh::generate
