#include "keymesh/analyze/topology.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <limits>
#include <string>
#include <span>
#include <vector>

#include "keymesh/core/equal_mask.hpp"  // emmintrin.h too, with SSE2
#include "keymesh/core/array.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/core/free_storage.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh::analyze {

namespace {

// Lock-free union-find over point ids. Roots are always linked under the
// smaller index, so the final partition (and every count taken from it) is
// the same whatever order threads perform the unions in.
class ConcurrentUnionFind {
 public:
  explicit ConcurrentUnionFind(Id n) : parent_(static_cast<std::size_t>(n)) {
    parallel::for_each(n, [&](Id i) { parent_[i] = static_cast<std::uint32_t>(i); });
  }
  // x's parent as last seen: equal hints mean one class (a cheap skip of
  // unite; unequal ones prove nothing).
  std::uint32_t parent_hint(std::uint32_t x) { return ref(x).load(std::memory_order_relaxed); }
  std::uint32_t find(std::uint32_t x) {
    for (;;) {
      std::uint32_t p = ref(x).load(std::memory_order_acquire);
      if (p == x) return x;
      const std::uint32_t gp = ref(p).load(std::memory_order_acquire);
      // Path halving: point x at its grandparent if nobody changed it meanwhile.
      if (gp != p) ref(x).compare_exchange_weak(p, gp, std::memory_order_acq_rel, std::memory_order_relaxed);
      x = gp;
    }
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    for (;;) {
      a = find(a);
      b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);
      std::uint32_t expected = a;  // a must still be a root when it is linked
      if (ref(a).compare_exchange_strong(expected, b, std::memory_order_acq_rel, std::memory_order_relaxed)) return;
    }
  }

 private:
  std::atomic_ref<std::uint32_t> ref(std::uint32_t i) { return std::atomic_ref<std::uint32_t>(parent_[i]); }
  std::vector<std::uint32_t> parent_;
};

// One neighbour entry of a vertex's fan: the point across an edge, the cell
// that edge belongs to and the local corner slot (for the local union-find).
struct FanEntry {
  std::uint64_t key;    // neighbour point << 32 | cell
  std::uint32_t local;
};

// Insertion sort for the short lists of a point's fan (typically 6 to 12
// entries); std::sort only for the rare high-valence point.
template <class T, class Less>
void small_sort(T* first, T* last, Less less) {
  if (last - first > 32) {
    std::sort(first, last, less);
    return;
  }
  for (T* i = first + 1; i < last; ++i) {
    T x = *i;
    T* j = i;
    for (; j > first && less(x, *(j - 1)); --j) *j = *(j - 1);
    *j = x;
  }
}

std::uint32_t local_find(std::uint32_t* parent, std::uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

void local_unite(std::uint32_t* parent, std::uint32_t a, std::uint32_t b) {
  a = local_find(parent, a);
  b = local_find(parent, b);
  if (a != b) parent[std::max(a, b)] = std::min(a, b);
}

// Maps a float to an unsigned integer with the same order (and -0 to +0), so
// equal floats get equal keys.
std::uint32_t sortable_bits(float f) {
  if (f == 0.0f) f = 0.0f;
  const std::uint32_t u = std::bit_cast<std::uint32_t>(f);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

// A hash of a point's position that equal positions share: the coordinates'
// sortable bits (-0 as +0), mixed (murmur3's finaliser).
std::uint64_t position_hash(const float* p) {
  std::uint64_t h = (std::uint64_t{sortable_bits(p[0])} | std::uint64_t{sortable_bits(p[1])} << 32) ^
                    std::uint64_t{sortable_bits(p[2])} * 0x9E3779B97F4A7C15ull;
  h ^= h >> 33, h *= 0xff51afd7ed558ccdull, h ^= h >> 33, h *= 0xc4ceb9fe1a85ec53ull, h ^= h >> 33;
  return h;
}

bool same_position(const float* p, const float* q) { return p[0] == q[0] && p[1] == q[1] && p[2] == q[2]; }
bool has_nan(const float* p) { return p[0] != p[0] || p[1] != p[1] || p[2] != p[2]; }

// The points of one run of equal hashes that repeat an earlier one's
// position: each compared with the run's distinct positions so far (nearly
// every run holds one position); past kDistinct of them, sorted by their
// coordinates' sortable bits and neighbours compared (a run of many
// positions only when hashes collide, or for a crafted input).
Id duplicates_in_run(std::uint32_t* run, Id length, const float* xyz) {
  constexpr int kDistinct = 16;
  const float* distinct[kDistinct];
  int seen = 0;
  Id dups = 0;
  for (Id k = 0; k < length; ++k) {
    const float* p = xyz + 3 * Id{run[k]};
    if (has_nan(p)) continue;  // NaN never equals
    bool repeated = false;
    for (int r = 0; r < seen && !repeated; ++r) repeated = same_position(p, distinct[r]);
    if (repeated) {
      ++dups;
    } else if (seen < kDistinct) {
      distinct[seen++] = p;
    } else {
      auto bits = [&](std::uint32_t i) {
        const float* q = xyz + 3 * Id{i};
        return std::array<std::uint32_t, 3>{sortable_bits(q[0]), sortable_bits(q[1]), sortable_bits(q[2])};
      };
      std::sort(run, run + length, [&](std::uint32_t a, std::uint32_t b) { return bits(a) < bits(b); });
      dups = 0;
      for (Id j = 1; j < length; ++j) {
        if (same_position(xyz + 3 * Id{run[j]}, xyz + 3 * Id{run[j - 1]})) ++dups;  // NaN never equals
      }
      return dups;
    }
  }
  return dups;
}

}  // namespace

namespace detail {

// Points whose position equals (float ==) an earlier point's. A radix sort
// by a hash of the position groups equal positions into runs, which
// duplicates_in_run counts. (A sort by x, then by (y, z) within runs of
// equal x, cost about 1 G instructions more on a 3.7 M-triangle contour,
// whose points share an x along whole grid planes.) As many hash bits as the points need
// to spread out (two radix passes up to 2^21 points), or `hash_bits`.
Id count_duplicate_points(const float* xyz, Id n, int hash_bits) {
  if (n < 2) return 0;
  std::vector<std::uint32_t> keys(static_cast<std::size_t>(n)), perm(static_cast<std::size_t>(n));
  const int bits = hash_bits > 0 ? std::min(32, hash_bits)
                                 : std::min(32, std::max(11, parallel::bits_needed(static_cast<std::uint64_t>(n)) + 1));
  parallel::for_each(n, [&](Id i) {
    keys[i] = static_cast<std::uint32_t>(position_hash(xyz + 3 * i) >> (64 - bits));
    perm[i] = static_cast<std::uint32_t>(i);
  });
  parallel::sort_pairs(keys, perm, bits);
  // Runs of equal hash, found per fixed chunk (a run crossing a chunk
  // boundary is owned by the chunk where it starts).
  const int chunks = parallel::chunk_count(n, 1 << 15);
  std::vector<Id> dups(std::max(chunks, 1), 0);
  parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
    Id i = b;
    while (i > 0 && i < n && keys[i] == keys[i - 1]) ++i;  // run started in the previous chunk
    while (i < e) {
      Id j = i + 1;
      while (j < n && keys[j] == keys[i]) ++j;
      if (j - i > 1) dups[c] += duplicates_in_run(perm.data() + i, j - i, xyz);
      i = j;
    }
  });
  Id total = 0;
  for (Id d : dups) total += d;
  return total;
}

}  // namespace detail

namespace {

struct ChunkCounts {
  Id edges = 0, boundary = 0, nonmanifold_edges = 0, nonmanifold_vertices = 0, unused = 0;
};

// Offsets, sizes and point ids a report can trust; the first out-of-range
// id whatever the thread count.
void check_layout(const SurfaceMesh& mesh) {
  if (mesh.points.size() % 3 != 0)
    throw InputError("check_topology: " + std::to_string(mesh.points.size()) + " point coordinates, not a multiple of 3");
  const Id n = mesh.num_points();
  const auto& conn = mesh.connectivity;
  const Id corners = static_cast<Id>(conn.size());
  if (mesh.offsets.empty()) {
    if (corners % 3 != 0)
      throw InputError("check_topology: triangle connectivity size " + std::to_string(corners) + " is not a multiple of 3");
  } else {
    if (mesh.offsets.front() != 0 || mesh.offsets.back() != conn.size())
      throw InputError("check_topology: cell offsets do not span the connectivity");
    for (std::size_t c = 0; c + 1 < mesh.offsets.size(); ++c)
      if (mesh.offsets[c + 1] < mesh.offsets[c])
        throw InputError("check_topology: cell offsets decrease at cell " + std::to_string(c));
  }
  const Id m = mesh.num_cells();
  if (n > Id{std::numeric_limits<std::uint32_t>::max()} || corners > Id{std::numeric_limits<std::uint32_t>::max()} ||
      m > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("check_topology: more than 2^32 - 1 points, cells or cell corners");
  const int chunks = parallel::chunk_count(corners, 1 << 16);
  std::vector<Id> first_bad(std::max(chunks, 1), corners);
  parallel::for_each_chunk(corners, chunks, [&](Id b, Id e, int c) {
    for (Id i = b; i < e; ++i)
      if (Id{conn[i]} >= n) {
        first_bad[c] = i;
        break;
      }
  });
  const Id bad = *std::min_element(first_bad.begin(), first_bad.end());
  if (bad < corners)
    throw InputError("check_topology: cell point id " + std::to_string(conn[bad]) + " out of range (" +
                     std::to_string(n) + " points)");
}

// Corners grouped by point (CSR: point v's corners are order[start[v] ..
// start[v + 1]), in increasing order). The corners are cut into a few
// chunks, each counting its corners per point in an array of its own (no
// atomic increment: one cost about 20 cycles here, more than the rest of
// the grouping), and each then placing them from its own cursors, so every
// list comes out sorted whatever the thread count. At most one chunk per
// corner a point (a triangle mesh has about six): the counts take no more
// memory than `order`.
using CornerOrder = std::vector<std::uint32_t, DefaultInitAllocator<std::uint32_t>>;
void corners_by_point(const SurfaceMesh& mesh, std::vector<Id>& start, CornerOrder& order) {
  const Id n = mesh.num_points();
  const auto& conn = mesh.connectivity;
  const Id corners = static_cast<Id>(conn.size());
  start.assign(static_cast<std::size_t>(n) + 1, 0);
  order.resize(static_cast<std::size_t>(corners));
  if (n == 0) return;
  const int chunks = static_cast<int>(std::clamp<Id>(corners / n, 1, parallel::chunk_count(corners, 1 << 16)));
  // cursor[c * n + v]: chunk c's corners at v, then the slot of its first.
  std::vector<std::uint32_t> cursor(static_cast<std::size_t>(chunks * n), 0);
  parallel::for_each_chunk(corners, chunks, [&](Id b, Id e, int c) {
    std::uint32_t* count = cursor.data() + c * n;
    for (Id i = b; i < e; ++i) ++count[conn[i]];
  });
  parallel::for_each(n, [&](Id v) {
    Id d = 0;
    for (int c = 0; c < chunks; ++c) d += cursor[c * n + v];
    start[v] = d;
  });
  parallel::exclusive_scan(start.data(), start.data(), n + 1);
  parallel::for_each(n, [&](Id v) {
    auto slot = static_cast<std::uint32_t>(start[v]);
    for (int c = 0; c < chunks; ++c) {
      const std::uint32_t count = cursor[c * n + v];
      cursor[c * n + v] = slot;
      slot += count;
    }
  });
  parallel::for_each_chunk(corners, chunks, [&](Id b, Id e, int c) {
    std::uint32_t* next = cursor.data() + c * n;
    for (Id i = b; i < e; ++i) order[next[conn[i]]++] = static_cast<std::uint32_t>(i);
  });
}

// The fan of point v (its d corners at list): every edge from v is counted
// at its smaller end point, with how many cells use it; the corners are
// united through shared edges and repeated cells, and more than one class
// makes v non-manifold. `ent` and `par` are scratch for 2d and d entries.
// The list is in increasing corner order (corners_by_point), so a cell's
// corners at v are next to each other.
struct FanPass {
  const SurfaceMesh& mesh;
  const std::vector<std::uint32_t>& corner_cell;  // empty for triangles
  std::vector<std::uint8_t>& degenerate;

  // The cell of a corner and the corners before and after it in the cell.
  void neighbours(Id corner, Id& c, Id& prev, Id& next) const {
    if (corner_cell.empty()) {
      c = corner / 3;
      const Id b = 3 * c;
      const Id at = corner - b;
      prev = b + (at == 0 ? 2 : at - 1);
      next = b + (at == 2 ? 0 : at + 1);
    } else {
      c = corner_cell[corner];
      const Id b = static_cast<Id>(mesh.offsets[c]);
      const Id e = static_cast<Id>(mesh.offsets[c + 1]);
      prev = corner == b ? e - 1 : corner - 1;
      next = corner + 1 == e ? b : corner + 1;
    }
  }

  void operator()(Id v, const std::uint32_t* list, Id d, FanEntry* ent, std::uint32_t* par, ChunkCounts& cc) const {
    if (triangle_fan(v, list, d, cc)) return;
    const auto& conn = mesh.connectivity;
    Id ne = 0;
    Id prev_cell = -1;
    for (Id j = 0; j < d; ++j) {
      Id c, prev, next;
      neighbours(list[j], c, prev, next);
      const auto lj = static_cast<std::uint32_t>(j);
      par[j] = lj;
      const auto cell_bits = static_cast<std::uint64_t>(c);
      ent[ne++] = {(std::uint64_t{conn[prev]} << 32) | cell_bits, lj};
      ent[ne++] = {(std::uint64_t{conn[next]} << 32) | cell_bits, lj};
      // Two corners of one cell at the same point: the cell repeats an id.
      if (c == prev_cell) {
        std::atomic_ref<std::uint8_t>(degenerate[c]).store(1, std::memory_order_relaxed);
        local_unite(par, lj, lj - 1);
      }
      prev_cell = c;
    }
    small_sort(ent, ent + ne, [](const FanEntry& a, const FanEntry& b) { return a.key < b.key; });
    for (Id g = 0; g < ne;) {
      const std::uint64_t w = ent[g].key >> 32;
      Id h = g + 1;
      Id distinct = 1;
      for (; h < ne && (ent[h].key >> 32) == w; ++h) {
        if (ent[h].key != ent[h - 1].key) ++distinct;
        local_unite(par, ent[g].local, ent[h].local);
      }
      // An edge from v to itself only marks a degenerate cell (already flagged).
      if (w > static_cast<std::uint64_t>(v)) {
        ++cc.edges;
        if (distinct == 1) ++cc.boundary;
        if (distinct >= 3) ++cc.nonmanifold_edges;
      }
      g = h;
    }
    Id fans = 0;
    for (Id j = 0; j < d; ++j)
      if (local_find(par, static_cast<std::uint32_t>(j)) == j) ++fans;
    if (fans > 1) ++cc.nonmanifold_vertices;
  }

  // The commonest point of a closed triangle mesh, counted at once: 2 to 8
  // corners (next[j], prev[j] their other points, padded with v to 8) whose
  // link edges next -> prev make one cycle through distinct points. Then
  // corner j's prev is exactly one corner's next (its successor around v),
  // every successor differs, and following them from corner 0 comes back
  // after d steps; every edge from v has two cells, so only edges are
  // counted (at their smaller end, once each: the next points are
  // distinct). Such a cycle never passes through v and no corner's two
  // points are one (that would be a shorter cycle). False, having counted
  // nothing, for any other point. (A triangle (v, v, w) makes a cycle of
  // its two corners, which is all of them only when d = 2, and then the
  // padding, v, matches its prev too; the one corner of a triangle (v, w,
  // w) is a cycle by itself, hence d >= 2.)
  static bool closed_disk(PointIndex self, const PointIndex* next, const PointIndex* prev, Id d, ChunkCounts& cc) {
#if defined(__SSE2__)
    if (d < 2 || d > 8) return false;
    const __m128i n0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(next)),
                  n1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(next + 4));
    unsigned successor[8];
    for (Id j = 0; j < d; ++j) {
      const __m128i wide = _mm_set1_epi32(static_cast<int>(prev[j]));
      const auto m = static_cast<unsigned>(
          _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(n0, wide))) |
          _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(n1, wide))) << 4);
      if (!std::has_single_bit(m)) return false;  // (padding lanes hold v, never a prev)
      successor[j] = static_cast<unsigned>(std::countr_zero(m));
    }
    // Back at corner 0 after exactly d steps: the successors are then a
    // permutation of the corners, one cycle.
    unsigned at = 0;
    for (Id step = 1; step < d; ++step)
      if ((at = successor[at]) == 0) return false;  // a shorter cycle
    if (successor[at] != 0) return false;
    // Edges to the next points above v (unsigned compare: sign bits flipped;
    // the padding, v, is not above v).
    const __m128i flip = _mm_set1_epi32(static_cast<int>(0x80000000u)),
                  above = _mm_set1_epi32(static_cast<int>(self ^ 0x80000000u));
    const auto greater = static_cast<unsigned>(
        _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(_mm_xor_si128(n0, flip), above))) |
        _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(_mm_xor_si128(n1, flip), above))) << 4);
    cc.edges += std::popcount(greater);
    return true;
#else
    (void)self, (void)next, (void)prev, (void)d, (void)cc;
    return false;
#endif
  }

  // The same counts, for nearly every point of a triangle mesh: one with at
  // most kMatched corners, each in a triangle of three distinct points.
  // Then every corner is its own cell, and its two other points differ from
  // each other and from v, so an edge (v, w) is used by as many cells as
  // there are corners with w among their two other points, and two corners
  // are in one fan when they share one. Both are read off bit masks of the
  // corners holding each id (no sort, no union-find). False, having counted
  // nothing, for any other point.
  bool triangle_fan(Id v, const std::uint32_t* list, Id d, ChunkCounts& cc) const {
    constexpr Id kMatched = 64;
    if (!corner_cell.empty() || d > kMatched) return false;
    const auto& conn = mesh.connectivity;
    const auto self = static_cast<PointIndex>(v);
    // Each corner's next and previous points, padded with 8 v (never one of
    // them) for equal_mask and closed_disk.
    PointIndex next[kMatched + 8], prev[kMatched + 8];
    for (Id j = 0; j < d; ++j) {
      // The corner's place in its triangle, and the offsets of the corners after and before it.
      constexpr int kAfter[3] = {1, 1, -2}, kBefore[3] = {2, -1, -1};
      // (32-bit: corners are below 2^32, checked, and % 3 is then one multiply.)
      const std::uint32_t corner = list[j], at = corner % 3u;
      next[j] = conn[corner + kAfter[at]];
      prev[j] = conn[corner + kBefore[at]];
    }
#if defined(__SSE2__)
    const __m128i pad = _mm_set1_epi32(static_cast<int>(self));
    for (PointIndex* ends : {next, prev})
      _mm_storeu_si128(reinterpret_cast<__m128i*>(ends + d), pad),
          _mm_storeu_si128(reinterpret_cast<__m128i*>(ends + d + 4), pad);
#else
    for (Id j = d; j < d + 8; ++j) next[j] = prev[j] = self;
#endif
    if (closed_disk(self, next, prev, d, cc)) return true;
    for (Id j = 0; j < d; ++j)
      if (next[j] == self || prev[j] == self || next[j] == prev[j]) return false;
    // One edge counted at its smaller end, at the first corner holding its
    // other end (corners in list order, a corner's next before its prev).
    auto edge = [&](PointIndex w, std::uint64_t holders, std::uint64_t before) {
      if ((holders & before) || w < self) return;
      ++cc.edges;
      const int cells = std::popcount(holders);
      if (cells == 1) ++cc.boundary;
      if (cells >= 3) ++cc.nonmanifold_edges;
    };
    std::uint64_t sharing[kMatched];  // by corner: the corners sharing one of its points with it
    auto holders = [&](PointIndex w) { return equal_mask(next, d, w) | equal_mask(prev, d, w); };
#if defined(__SSE2__)
    // Up to 8 corners (nearly every point): the next and previous points in
    // four registers, compared with w at once, the four results packed into
    // one 16-bit mask (next's holders, then prev's).
    const __m128i n0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(next)),
                  n1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(next + 4)),
                  p0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(prev)),
                  p1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(prev + 4));
    auto holders_of_eight = [&](PointIndex w) {
      const __m128i wide = _mm_set1_epi32(static_cast<int>(w));
      const __m128i in_next = _mm_packs_epi32(_mm_cmpeq_epi32(n0, wide), _mm_cmpeq_epi32(n1, wide));
      const __m128i in_prev = _mm_packs_epi32(_mm_cmpeq_epi32(p0, wide), _mm_cmpeq_epi32(p1, wide));
      const auto m = static_cast<unsigned>(_mm_movemask_epi8(_mm_packs_epi16(in_next, in_prev)));
      return std::uint64_t{(m | m >> 8) & 0xffu};
    };
#endif
    for (Id j = 0; j < d; ++j) {
#if defined(__SSE2__)
      const std::uint64_t with_next = d <= 8 ? holders_of_eight(next[j]) : holders(next[j]);
      const std::uint64_t with_prev = d <= 8 ? holders_of_eight(prev[j]) : holders(prev[j]);
#else
      const std::uint64_t with_next = holders(next[j]), with_prev = holders(prev[j]);
#endif
      const std::uint64_t before = (std::uint64_t{1} << j) - 1;
      edge(next[j], with_next, before);
      edge(prev[j], with_prev, before);
      sharing[j] = with_next | with_prev;
    }
    // The corners reached from corner 0 through shared points: one fan when
    // that is all of them.
    std::uint64_t reached = 1, frontier = 1;
    while (frontier) {
      std::uint64_t seen = 0;
      for (std::uint64_t m = frontier; m; m &= m - 1) seen |= sharing[std::countr_zero(m)];
      frontier = seen & ~reached;
      reached |= seen;
    }
    if (reached != (d == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << d) - 1)) ++cc.nonmanifold_vertices;
    return true;
  }
};

// Every point's fan, in fixed chunks; the counts summed into r.
void count_fans(const SurfaceMesh& mesh, const FanPass& fan, const std::vector<Id>& start,
                CornerOrder& order, TopologyReport& r, std::span<const std::uint8_t> counted) {
  const Id n = mesh.num_points();
  Id max_degree = 0;
  for (Id v = 0; v < n; ++v) max_degree = std::max(max_degree, start[v + 1] - start[v]);
  const int chunks = parallel::chunk_count(n, 1 << 12);
  std::vector<ChunkCounts> counts(std::max(chunks, 1));
  // Per-chunk scratch, padded apart by a few cache lines: threads writing
  // neighbouring bytes would otherwise ping-pong the lines between cores.
  const Id entry_stride = 2 * max_degree + 16;
  const Id parent_stride = max_degree + 64;
  std::vector<FanEntry> entries(static_cast<std::size_t>(std::max(chunks, 1) * entry_stride));
  std::vector<std::uint32_t> parents(static_cast<std::size_t>(std::max(chunks, 1) * parent_stride));
  parallel::for_each_chunk(n, chunks, [&](Id vb, Id ve, int chunk) {
    ChunkCounts cc;  // local: counts[] entries share cache lines
    for (Id v = vb; v < ve; ++v) {
      if (!counted.empty() && !counted[static_cast<std::size_t>(v)]) continue;
      const Id s = start[v], d = start[v + 1] - s;
      if (d == 0) {
        ++cc.unused;
        continue;
      }
      fan(v, order.data() + s, d, entries.data() + chunk * entry_stride, parents.data() + chunk * parent_stride, cc);
    }
    counts[chunk] = cc;
  });
  for (const ChunkCounts& cc : counts) {
    r.edges += cc.edges;
    r.boundary_edges += cc.boundary;
    r.nonmanifold_edges += cc.nonmanifold_edges;
    r.nonmanifold_vertices += cc.nonmanifold_vertices;
    r.unused_points += cc.unused;
  }
}

// Components: cells joined through shared points (points no cell uses are
// not components).
Id count_components(const SurfaceMesh& mesh, const std::vector<Id>& start) {
  const Id n = mesh.num_points();
  const auto& conn = mesh.connectivity;
  ConcurrentUnionFind uf(n);
  parallel::for_each(mesh.num_cells(), [&](Id c) {
    const std::uint64_t b = mesh.cell_begin(c), e = mesh.cell_end(c);
    for (std::uint64_t k = b + 1; k < e; ++k)
      if (uf.parent_hint(conn[b]) != uf.parent_hint(conn[k])) uf.unite(conn[b], conn[k]);
  }, 1 << 14);
  const int rc = parallel::chunk_count(n, 1 << 14);
  std::vector<Id> roots(std::max(rc, 1), 0);
  parallel::for_each_chunk(n, rc, [&](Id b, Id e, int c) {
    for (Id v = b; v < e; ++v)
      if (start[v + 1] > start[v] && uf.find(static_cast<std::uint32_t>(v)) == v) ++roots[c];
  });
  Id total = 0;
  for (Id x : roots) total += x;
  return total;
}

}  // namespace

namespace {
// check_fans' counts; `start` keeps the corners' grouping by point.
TopologyReport fans_of(const SurfaceMesh& mesh, std::vector<Id>& start, std::span<const std::uint8_t> counted = {}) {
  check_layout(mesh);
  TopologyReport r;
  const Id m = mesh.num_cells();
  r.points = mesh.num_points();
  r.cells = m;
  // Cell of every corner (implicit for triangles).
  std::vector<std::uint32_t> corner_cell;
  std::vector<std::uint8_t> degenerate(static_cast<std::size_t>(m), 0);
  if (!mesh.offsets.empty()) {
    corner_cell.resize(mesh.connectivity.size());
    parallel::for_each(m, [&](Id c) {
      const std::uint64_t b = mesh.offsets[c], e = mesh.offsets[c + 1];
      for (std::uint64_t k = b; k < e; ++k) corner_cell[k] = static_cast<std::uint32_t>(c);
      if (e - b < 3) degenerate[c] = 1;  // fewer than three points spans no area
    }, 1024);
  }
  CornerOrder order;
  corners_by_point(mesh, start, order);
  count_fans(mesh, FanPass{mesh, corner_cell, degenerate}, start, order, r, counted);
  free_storage(order);
  for (std::uint8_t f : degenerate) r.degenerate_cells += f;
  return r;
}
}  // namespace

TopologyReport check_fans(const SurfaceMesh& mesh) {
  std::vector<Id> start;
  return fans_of(mesh, start);
}

TopologyReport check_fans(const SurfaceMesh& mesh, std::span<const std::uint8_t> counted) {
  if (counted.size() != static_cast<std::size_t>(mesh.num_points()))
    throw InputError("check_fans: " + std::to_string(counted.size()) + " point marks for " +
                     std::to_string(mesh.num_points()) + " points");
  std::vector<Id> start;
  return fans_of(mesh, start, counted);
}

TopologyReport check_topology(const SurfaceMesh& mesh) {
  std::vector<Id> start;
  TopologyReport r = fans_of(mesh, start);
  const Id n = mesh.num_points(), m = mesh.num_cells();
  r.components = count_components(mesh, start);
  r.duplicate_points = detail::count_duplicate_points(mesh.points.data(), n);
  const Id used = n - r.unused_points;
  r.euler_characteristic = used - r.edges + m;
  r.closed_manifold = m > 0 && r.boundary_edges == 0 && r.nonmanifold_edges == 0 && r.nonmanifold_vertices == 0 &&
                      r.degenerate_cells == 0;
  return r;
}

}  // namespace keymesh::analyze
