#pragma once
// Coarsening in the contour's own pass (paper, Section 6.1): the structured
// plan of contour_rows.hpp with the coarse key in place of the edge key.
//
// A crossing's coarse key is the grid point nearest to it on its edge (the
// edge's first point when t < 0.5, its second otherwise). Coarsening merges
// the crossings that share one: one coarse point per key, the mean of its
// crossings' positions and fields, triangles rewritten with coarse ids and
// dropped when two of their corners merged. KEY-REDUCE's dense plan over the
// coarse keys numbers the coarse points by key rank; here, as for the edge
// keys, the rank comes from bits and counts instead of a table over the
// grid's points:
//   1. far     every grid row marks its cut edges whose crossing is nearer
//              the far end (t >= 0.5), one bit per edge and axis;
//   2. mark    a grid point is a candidate coarse point when a cut edge's
//              crossing is nearest to it: its own edges' near ends, the far
//              ends of the x edge before it and of the y and z edges
//              arriving from the rows below (word operations on the far and
//              cut bits);
//   3. tally   each cut voxel's coarse triangles looked up by its cube case
//              and far bits (coarse_cases.hpp: repeated corners and folds
//              within the voxel already decided) and the entry kept; every
//              voxel row counts its triangles and records its face
//              triangles;
//   4. folds   across the faces between voxels decided (coarse_folds.hpp),
//              then each voxel row's kept triangles counted and prefix
//              sums give its first: the caller allocates the triangles'
//              array once, at its final size;
//   5. fans    every candidate's fan read from its eight voxels' entries
//              (coarse_fans.hpp): candidates left without a triangle (all
//              their crossings' triangles collapsed) are dropped, and those
//              that may not be one closed fan listed for the split;
//   6. number  rows count their coarse points, prefix sums give every
//              64-point word its first id;
//   7. points  row by row, every crossing computed once and added to its
//              coarse point's running sums, code by code (CoarseRow), so
//              that each point sums its at most six crossings in the order
//              of their edge keys (the order a KEY-REDUCE over the fine
//              points would merge them in); then each point's mean written;
//   8. write   each voxel row's kept triangles written once, at their final
//              place, with coarse ids (from the kept entries: no second
//              lookup).
// The caller runs steps 1 to 6 for every isovalue, allocates the outputs,
// then runs 7 and 8. The fine points are never written. The bytes are those
// of coarsen() over the fine mesh (generate/coarsen.hpp): tests hold them
// equal. The caller then splits non-manifold points and edges
// (split_nonmanifold.hpp) among the listed suspects, as coarsen() does
// among all points.
#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "coarse_cases.hpp"
#include "coarse_folds.hpp"
#include "generate/contour/contour_rows.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/core/types.hpp"
#include "keymesh/core/uninitialized_array.hpp"
#include "keymesh/generate/contour/marching_cubes_table.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/scan.hpp"
#include "generate/contour/voxel_bits.hpp"

namespace keymesh::generate {

// One isovalue's far bits, coarse-point bits and ranks, by grid row of
// planes [0, nz), words_per_row words a row (the layout of InsideBits'
// rows). Only the rows that have cut edges hold far words, and only the
// live rows point words and first ids, each packed in row order (`slot`):
// on ch2better 62 % of the rows have cut edges, and a grid-sized array left
// unwritten was resident all the same where huge pages back it. The words
// are left uninitialised when sized: each is written before it is read.
struct CoarseBits {
  Id words_per_row = 0;
  KeptArray<std::uint64_t> far;     // (far_slot[r] * 3 + axis) * words_per_row + q; rows with cut edges
  KeptArray<std::uint64_t> points;  // live_slot[r] * words_per_row + q: coarse points; live rows
  KeptArray<std::uint32_t> first;   // live_slot[r] * words_per_row + q: id of the word's first coarse point
  std::vector<std::uint8_t> cut;   // per row: has cut edges (its far words are written)
  std::vector<std::uint8_t> live;  // per row: may hold coarse points (its own cuts, or the rows below it have some)
  std::vector<std::uint32_t> far_slot;   // per row with cut edges: its rank among them
  std::vector<std::uint32_t> live_slot;  // per live row: its rank among them
  std::vector<std::uint64_t> zeros;  // a row of zero words: the far bits of a row without cut edges
  Id count = 0;                    // coarse points of this isovalue

  std::uint64_t* far_words(Id r) { return far.data() + Id{far_slot[r]} * 3 * words_per_row; }
  const std::uint64_t* far_row(Id r, int axis) const {
    return cut[r] ? far.data() + (Id{far_slot[r]} * 3 + axis) * words_per_row : zeros.data();
  }
  // A live row's coarse-point words and their first ids.
  std::uint64_t* point_words(Id r) { return points.data() + Id{live_slot[r]} * words_per_row; }
  const std::uint64_t* point_words(Id r) const { return points.data() + Id{live_slot[r]} * words_per_row; }
  std::uint32_t* first_ids(Id r) { return first.data() + Id{live_slot[r]} * words_per_row; }
  const std::uint32_t* first_ids(Id r) const { return first.data() + Id{live_slot[r]} * words_per_row; }

  // The far bits a grid row (j, k) = r reads: its own three axes', the y
  // edges of row (j - 1, k) and the z edges of row (j, k - 1) (null at the
  // grid's border or without cut edges), whose far ends are this row's points.
  struct Around {
    const std::uint64_t *x, *y, *z, *y_below, *z_below;
  };
  Around around(Id r, Id j, Id k, Id ny) const {
    return {far_row(r, 0), far_row(r, 1), far_row(r, 2), j > 0 && cut[r - 1] ? far_row(r - 1, 1) : nullptr,
            k > 0 && cut[r - ny] ? far_row(r - ny, 2) : nullptr};
  }

  // ids[i] = the coarse id of grid point i of row r, for its coarse points
  // (a row without any is left alone: no triangle has a corner there).
  void row_ids(Id r, std::uint32_t* ids) const {
    if (!live[r]) return;
    const std::uint64_t* p = point_words(r);
    const std::uint32_t* f = first_ids(r);
    for (Id q = 0; q < words_per_row; ++q) {
      std::uint32_t id = f[q];
      for (std::uint64_t w = p[q]; w; w &= w - 1) ids[64 * q + std::countr_zero(w)] = id++;
    }
  }
};

// Calls f(r, ahead) for every grid row r = k * ny + j, in parallel, by
// bricks of 16 rows by 8 planes (k outer, j inner within a brick): the rows
// a row reads around it (j - 1, k - 1, k + 1) were just read, so their
// samples and bits are still in cache. `ahead` is the row the brick visits
// 16 rows later, at the same j on the next plane (-1 on the brick's last
// plane), whose data f may ask for ahead of time. Which thread takes a row
// changes nothing.
template <class F>
void for_each_row_in_bricks_ahead(const GridShape& s, F&& f) {
  constexpr Id kRows = 16, kPlanes = 8;
  const Id j_bricks = (s.ny + kRows - 1) / kRows, k_bricks = (s.nz + kPlanes - 1) / kPlanes;
  parallel::for_each_dynamic(j_bricks * k_bricks, [&](Id b) {
    const Id j0 = (b % j_bricks) * kRows, k0 = (b / j_bricks) * kPlanes;
    const Id j_end = std::min(s.ny, j0 + kRows), k_end = std::min(s.nz, k0 + kPlanes);
    for (Id k = k0; k < k_end; ++k)
      for (Id j = j0; j < j_end; ++j) f(k * s.ny + j, k + 1 < k_end ? (k + 1) * s.ny + j : -1);
  }, 1);
}

// The same, calling f(r).
template <class F>
void for_each_row_in_bricks(const GridShape& s, F&& f) {
  for_each_row_in_bricks_ahead(s, [&](Id r, Id) { f(r); });
}

// Asks for the cache lines of samples that hold the bits of mask `m` of
// word q, in each of `rows`.
template <class T>
[[gnu::always_inline]] inline void prefetch_samples(const T* const* rows, int n_rows, Id q, std::uint64_t m) {
  constexpr int kPerLine = sizeof(T) >= 64 ? 1 : 64 / static_cast<int>(sizeof(T));
  constexpr std::uint64_t kLineMask = kPerLine >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << kPerLine) - 1;
  for (int g = 0; g < 64; g += kPerLine)
    if ((m >> g) & kLineMask)
      for (int r = 0; r < n_rows; ++r) __builtin_prefetch(rows[r] + 64 * q + g);
}

// Asks for the samples at the cut edges of grid row (j, k), `cuts` its
// RowCuts: both ends of each, in its own row and in the rows its y and z
// edges reach.
template <class T>
[[gnu::always_inline]] inline void prefetch_cut_samples(const T* samples, const GridShape& s, const RowCuts& cuts,
                                                        Id j, Id k) {
  const T* const row = samples + j * s.nx + k * s.nxy;
  // (No pointer past the grid: the last row and plane have no y or z edges.)
  const T* const rows3[3] = {row, cuts.next_y ? row + s.stride[1] : row, cuts.next_z ? row + s.stride[2] : row};
  for (Id q = 0; q < cuts.data_words; ++q) {
    const RowCuts::Words w = cuts.word(q);
    prefetch_samples(rows3, 1, q, w.x | w.y | w.z);
    if (w.y) prefetch_samples(rows3 + 1, 1, q, w.y);
    if (w.z) prefetch_samples(rows3 + 2, 1, q, w.z);
  }
}

// Steps 1 and 2 for one isovalue: far bits (nearer_far(v0, v1) says whether
// the crossing on a cut edge with end samples v0, v1 has t >= 0.5) and the
// candidate coarse points (numbered by number_coarse_points, once
// check_coarse_fans has taken out those left without a triangle). `rc`
// (the rows' counts) says which rows have cut edges: only those and the
// rows above them are visited.
template <class T, class NearerFar>
void mark_coarse_points(const InsideBits& bits, const GridShape& s, const RowCounts& rc, const T* samples,
                        const NearerFar& nearer_far, CoarseBits& cb) {
  const Id wpr = bits.words_per_row, rows = s.ny * s.nz, last_plane = s.nz - 1;
  // Row slots are 32-bit (checked before anything is sized).
  if (rows > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("contour --coarsen: " + std::to_string(rows) + " grid rows exceed 2^32 - 1");
  cb.words_per_row = wpr;
  cb.zeros.assign(static_cast<std::size_t>(wpr), 0);
  cb.cut.resize(static_cast<std::size_t>(rows));
  cb.live.resize(static_cast<std::size_t>(rows));
  cb.far_slot.resize(static_cast<std::size_t>(rows));
  cb.live_slot.resize(static_cast<std::size_t>(rows));
  parallel::for_each(rows, [&](Id r) { cb.cut[r] = rc.point_first[r + 1] != rc.point_first[r]; });
  parallel::for_each(rows, [&](Id r) {
    cb.live[r] = cb.cut[r] || (r % s.ny > 0 && cb.cut[r - 1]) || (r >= s.ny && cb.cut[r - s.ny]);
    cb.far_slot[r] = cb.cut[r];
    cb.live_slot[r] = cb.live[r];
  });
  const Id cut_rows = parallel::exclusive_scan(cb.far_slot.data(), cb.far_slot.data(), rows);
  const Id live_rows = parallel::exclusive_scan(cb.live_slot.data(), cb.live_slot.data(), rows);
  cb.far.room_for(static_cast<std::size_t>(3 * wpr * cut_rows));
  cb.points.room_for(static_cast<std::size_t>(wpr * live_rows));
  cb.first.room_for(static_cast<std::size_t>(wpr * live_rows));
  // The far bits read the samples at every cut edge, which in a volume
  // past the last-level cache are long gone since classify: a sparse
  // surface's rows then wait on a miss or two each, one row after another
  // (the 512^3 sphere: 48.5-49.5 ms of marking in a 126 ms coarsened
  // contour, 2 threads). So each row first asks for the lines its row one
  // plane up will read, 16 rows of work ahead (31.2-31.5 ms of 108).
  for_each_row_in_bricks_ahead(s, [&](Id r, Id ahead) {
    if (!cb.cut[r]) return;
    const Id j = r % s.ny, k = r / s.ny;
    if (ahead >= 0 && cb.cut[ahead])
      prefetch_cut_samples(samples, s, RowCuts(bits, s, ahead % s.ny, ahead / s.ny, last_plane), ahead % s.ny,
                           ahead / s.ny);
    std::uint64_t* f = cb.far_words(r);
    const RowCuts cuts(bits, s, j, k, last_plane);
    // The row's samples and those one step along each axis, held in
    // registers (through a functor of (i, j, k, axis) every edge recomputed
    // its point and reloaded the arrays).
    const T* const row = samples + j * s.nx + k * s.nxy;
    const T* const along[3] = {row + s.stride[0], row + s.stride[1], row + s.stride[2]};
    // A word's far bits gathered in registers, one axis at a time, without
    // a branch on the outcome (a coin toss on a real surface).
    for (Id q = 0; q < wpr; ++q) {
      const RowCuts::Words w = cuts.word(q);
      const std::uint64_t cut[3] = {w.x, w.y, w.z};
      const T* const here = row + 64 * q;
      for (int a = 0; a < 3; ++a) {
        const T* const there = along[a] + 64 * q;
        std::uint64_t out = 0;
        for (std::uint64_t m = cut[a]; m; m &= m - 1) {
          const int b = std::countr_zero(m);
          out |= static_cast<std::uint64_t>(nearer_far(here[b], there[b])) << b;
        }
        f[a * wpr + q] = out;
      }
    }
  });
  for_each_row_in_bricks(s, [&](Id r) {
    if (!cb.live[r]) return;
    const Id j = r % s.ny, k = r / s.ny;
    const RowCuts cuts(bits, s, j, k, last_plane);
    const auto [fx, fy, fz, fy_below, fz_below] = cb.around(r, j, k, s.ny);
    std::uint64_t* out = cb.point_words(r);
    std::uint64_t carry = 0;  // far x edge of the previous word's last point
    for (Id q = 0; q < wpr; ++q) {
      const RowCuts::Words w = cuts.word(q);
      // Far bits are a subset of the cut bits: cut ^ far are the near ends.
      std::uint64_t c = (w.x ^ fx[q]) | (w.y ^ fy[q]) | (w.z ^ fz[q]) | (fx[q] << 1) | carry;
      carry = fx[q] >> 63;
      if (fy_below) c |= fy_below[q];
      if (fz_below) c |= fz_below[q];
      out[q] = c;
    }
  });
}

// Numbers the coarse points (cb.points' bits) in key order, starting at
// `first_id`: rows count them, prefix sums give every 64-point word its
// first id. Sets cb.count.
inline void number_coarse_points(const GridShape& s, Id first_id, CoarseBits& cb) {
  const Id rows = s.ny * s.nz, wpr = cb.words_per_row;
  std::vector<Id> row_first(static_cast<std::size_t>(rows + 1), 0);
  auto row_words = [&](Id r) { return cb.point_words(r); };
  parallel::for_each(rows, [&](Id r) {
    if (!cb.live[r]) return;
    Id count = 0;
    for (Id q = 0; q < wpr; ++q) count += std::popcount(row_words(r)[q]);
    row_first[r] = count;
  });
  cb.count = parallel::exclusive_scan(row_first.data(), row_first.data(), rows + 1);
  parallel::for_each(rows, [&](Id r) {
    if (!cb.live[r]) return;
    auto id = static_cast<std::uint32_t>(first_id + row_first[r]);
    std::uint32_t* first = cb.first_ids(r);
    for (Id q = 0; q < wpr; ++q) first[q] = id, id += static_cast<std::uint32_t>(std::popcount(row_words(r)[q]));
  });
}

// A crossing merged into a coarse point: its edge, by first grid point and axis.
struct CoarseCrossing {
  Id i, j, k;
  int axis;
};

// A coarse point's crossings by code, in edge-key order (keys 3 p + axis
// grow with p = i + j nx + k nxy): 0 the z edge from the plane below, 1 the
// y edge from the row below, 2 the x edge from the point before, then 3, 4,
// 5 the point's own x, y, z edges. The crossing of code c at point (i, j, k).
constexpr CoarseCrossing crossing_at(Id i, Id j, Id k, int code) {
  constexpr int kAxis[6] = {2, 1, 0, 0, 1, 2};
  const int a = kAxis[code];
  const Id back = code < 3 ? 1 : 0;
  return {i - (a == 0 ? back : 0), j - (a == 1 ? back : 0), k - (a == 2 ? back : 0), a};
}

// The coarse points of grid row (j, k) and their crossings, read off the
// row's bits word by word: the coarse points, their first ids, the cut
// bits (RowCuts) and the far bits around the row (CoarseBits::around).
// Each crossing of the grid belongs to exactly one (point, code) of one
// row.
struct CoarseRow {
  Id j, k;
  const std::uint64_t* points;  // the row's coarse-point words
  const std::uint32_t* first;   // the id of each word's first coarse point
  RowCuts cuts;
  CoarseBits::Around far;
  // The words holding coarse points, increasing (a crossing's word is its
  // point's): a sparse surface's rows have a point or two in a word of
  // several, and each code's loop visits only these.
  const Id* words;
  Id word_count;

  // Calls f(i, crossing, std::integral_constant<int, axis>) for every
  // crossing of the row's points (not of a candidate check_coarse_fans
  // dropped for want of a triangle), i its point, code after code: all of
  // code 0's, then code 1's, ... so that each point meets its crossings in
  // edge-key order, the order in which a KEY-REDUCE over the fine points
  // merges them. By code rather than by point: each loop is one kind of
  // edge (a fixed axis and fixed sample offsets), with no per-point list of
  // codes to build and walk.
  template <class F>
  [[gnu::always_inline]] void for_each_crossing(F&& f) const {
    if (far.z_below) by_code<0>(f);
    if (far.y_below) by_code<1>(f);
    by_code<2>(f), by_code<3>(f);
    if (cuts.next_y) by_code<4>(f);
    if (cuts.next_z) by_code<5>(f);
  }

  // Calls f(i, id) for every coarse point i of the row, in increasing i.
  template <class F>
  [[gnu::always_inline]] void for_each_point(F&& f) const {
    for (const Id q : std::span(words, static_cast<std::size_t>(word_count))) {
      std::uint32_t id = first[q];
      for (std::uint64_t m = points[q]; m; m &= m - 1) f(64 * q + std::countr_zero(m), id++);
    }
  }

 private:
  // Word q of the points that have crossing `Code` (the far bits are a
  // subset of the cut bits: cut ^ far are the near ends).
  template <int Code>
  [[gnu::always_inline]] std::uint64_t with_code(Id q) const {
    if constexpr (Code == 0) return far.z_below[q];
    if constexpr (Code == 1) return far.y_below[q];
    if constexpr (Code == 2) return (far.x[q] << 1) | (q > 0 ? far.x[q - 1] >> 63 : 0);
    if constexpr (Code == 3) {
      const std::uint64_t a = cuts.in[q];
      const std::uint64_t x = a ^ ((a >> 1) | (cuts.in[q + 1] << 63));
      return (q == cuts.last_x_word ? x & cuts.last_x_mask : x) ^ far.x[q];
    }
    if constexpr (Code == 4) return cuts.in[q] ^ cuts.next_y[q] ^ far.y[q];
    if constexpr (Code == 5) return cuts.in[q] ^ cuts.next_z[q] ^ far.z[q];
  }

  template <int Code, class F>
  [[gnu::always_inline]] void by_code(F& f) const {
    constexpr int axis = crossing_at(0, 0, 0, Code).axis;
    for (const Id q : std::span(words, static_cast<std::size_t>(word_count)))
      for (std::uint64_t m = with_code<Code>(q) & points[q]; m; m &= m - 1) {
        const Id i = 64 * q + std::countr_zero(m);
        f(i, crossing_at(i, j, k, Code), std::integral_constant<int, axis>{});
      }
  }
};

// Step 7: calls f(row) for every grid row (CoarseRow) that holds coarse
// points of the isovalue. With `samples`, each row first asks for the
// sample lines its row one plane up (`ahead`) will read: at its points and
// the point before each (the x edge arriving), in its own row and the rows
// its y and z edges reach, and the row below it (the y edges arriving). The
// 512^3 sphere's points took 24.5-25.5 ms of a 105-108 ms coarsened contour
// without (2 threads), most of it waiting on samples; 13.4-13.6 ms with.
template <class F, class T = std::uint8_t>
void for_each_coarse_row(const InsideBits& bits, const GridShape& s, const CoarseBits& cb, F&& f,
                         const T* samples = nullptr) {
  const Id wpr = cb.words_per_row, last_plane = s.nz - 1;
  for_each_row_in_bricks_ahead(s, [&](Id r, Id ahead) {
    if (samples && ahead >= 0 && cb.live[ahead]) {
      const Id ja = ahead % s.ny, ka = ahead / s.ny;
      const T* const a_row = samples + ja * s.nx + ka * s.nxy;
      // Its own row, the next along y and z, the one before along y: all
      // four off the grid's border, else its own only (no pointer off the
      // grid).
      const bool inner = ka < last_plane && ja > 0 && ja + 1 < s.ny;
      const T* const rows[4] = {a_row, inner ? a_row + s.stride[1] : a_row, inner ? a_row + s.stride[2] : a_row,
                                inner ? a_row - s.stride[1] : a_row};
      const int n = inner ? 4 : 1;
      const std::uint64_t* const pw = cb.point_words(ahead);
      for (Id q = 0; q < wpr; ++q)
        if (pw[q]) prefetch_samples(rows, n, q, pw[q] | (pw[q] >> 1));
    }
    if (!cb.live[r]) return;
    const std::uint64_t* const points = cb.point_words(r);
    thread_local std::vector<Id> words;
    words.resize(static_cast<std::size_t>(wpr));
    Id count = 0;
    for (Id q = 0; q < wpr; ++q) {
      words[count] = q;
      count += points[q] != 0;
    }
    if (!count) return;
    const Id j = r % s.ny, k = r / s.ny;
    f(CoarseRow{j, k, points, cb.first_ids(r), RowCuts(bits, s, j, k, last_plane), cb.around(r, j, k, s.ny),
                words.data(), count});
  });
}

// The far bits a voxel row's cut voxels read: those of its four corner rows
// (by corner bits y | z << 1): the x edges of all four, the y edges of rows
// 0 and 2, the z edges of rows 0 and 1, in the order of a far key's bits
// (coarse_cases.hpp, kFarKeyEdge). A word's 64 voxels' far bytes are made
// at once by the transpose that makes their cube cases (bytes_of_words),
// and a voxel's far key is two of them: its point's and the next's.
// (It replaced far bytes per grid point of a brick's rows, built for every
// point of a word with a cut edge, then read six times a voxel: ch2better,
// callgrind, 1 thread: the tally 308 M -> 238 M instructions.)
class VoxelRowFar {
 public:
  VoxelRowFar(const CoarseBits& cb, const GridShape& s, Id j, Id k) {
    const Id r = k * s.ny + j;
    for (int row = 0; row < 4; ++row) words_[row] = cb.far_row(r + (row & 1) + (row >> 1) * s.ny, 0);
    words_[4] = cb.far_row(r, 1), words_[5] = cb.far_row(r, 2);
    words_[6] = cb.far_row(r + s.ny, 1), words_[7] = cb.far_row(r + 1, 2);
  }

  // bytes[b], b in [0, 64]: the far byte of point 64 q + b (bit n: far
  // key bit n; point 64 q + 64's only bits 4-7, from word q + 1, which the
  // far rows have: a row's words include its padding word).
  [[gnu::always_inline]] void bytes_of_word(Id q, std::uint8_t bytes[65]) const {
    const std::uint64_t* const* w = words_;
    bytes_of_words(w[0][q], w[1][q], w[2][q], w[3][q], w[4][q], w[5][q], w[6][q], w[7][q], bytes);
    unsigned next = 0;
    for (int n = 4; n < 8; ++n) next |= static_cast<unsigned>(w[n][q + 1] & 1u) << n;
    bytes[64] = static_cast<std::uint8_t>(next);
  }

  // The far key of the voxel at `bit` of a word, from its bytes.
  [[gnu::always_inline]] static unsigned key(const std::uint8_t* bytes, int bit) {
    std::uint16_t k;
    std::memcpy(&k, bytes + bit, sizeof k);
    return k;
  }

 private:
  const std::uint64_t* words_[8];
};

// One isovalue's coarse triangles between their passes, kept by the caller
// across isovalues and calls. By brick (contour_rows.hpp's VoxelBricks):
// its cut voxels (position along the row, table entry) and its face
// triangles; by voxel row: its cut voxels, its range of face triangles, its
// triangle count, then its first triangle.
struct CoarseTriangles {
  // Room for the brick's cut voxels (a bound from its rows' cut edges) and
  // face triangles (grown when a voxel might not fit); only the elements
  // written are touched.
  std::vector<KeptArray<std::uint32_t>> voxel_i;  // each cut voxel's i, in walk order
  std::vector<KeptArray<std::uint16_t>> entries;  // CoarseVoxelTable::index of each cut voxel, in walk order
  std::vector<KeptArray<FaceTriangle>> faces;     // its rows' one after the other
  std::vector<std::uint32_t> voxels;      // by voxel row: its cut voxels
  std::vector<std::uint32_t> entry_first; // by voxel row: its first cut voxel in its brick's arrays
  std::vector<std::uint32_t> face_first;  // by voxel row: its first record in its brick's
  std::vector<std::uint32_t> face_count;  // by voxel row
  std::vector<Id> first;                  // by voxel row: its triangles (tally), then its first (fold_and_count)
  std::vector<std::uint8_t> folded;       // by voxel row: fold_across_faces dropped some of its triangles
  std::vector<Id> fine;                   // by brick: its voxels' fine triangles (marching cubes')
  Id count = 0;                           // triangles kept
  Id fine_triangles = 0;                  // the isovalue's fine triangles (what coarsening started from)

  // Sizes the by-brick and by-voxel-row arrays (their elements written by the tally).
  void size_for(std::size_t bricks, std::size_t voxel_rows) {
    if (faces.size() < bricks) faces.resize(bricks), entries.resize(bricks), voxel_i.resize(bricks);
    voxels.resize(voxel_rows);
    entry_first.resize(voxel_rows);
    face_first.resize(voxel_rows);
    face_count.resize(voxel_rows);
    first.resize(voxel_rows + 1);
    fine.assign(bricks, 0);
  }

  FaceTriangle* faces_of(const VoxelBricks& bricks, Id ny, Id vr) const {
    return faces[bricks.brick_of(vr % (ny - 1), vr / (ny - 1))].elements.get() + face_first[vr];
  }
};

// A brick's cut voxels, counted from the inside bits before the tally
// writes its records, so that these are sized exactly: a bound by cut edges
// (two voxels for every three) was 2.6 times the count on ch2better, and
// with huge pages the pages it left unwritten were resident all the same.
// `has_cuts(j, k)`: whether the voxel row's four grid rows have cut edges.
template <class HasCuts>
Id count_cut_voxels(const InsideBits& bits, const GridShape& s, const VoxelBricks& bricks, Id brick,
                    HasCuts&& has_cuts) {
  Id voxels = 0;
  for (Id k = bricks.k_begin(brick); k < bricks.k_end(brick); ++k)
    for (Id j = bricks.j_begin(brick); j < bricks.j_end(brick); ++j)
      if (has_cuts(j, k))
        for_each_cut_word(bits, s, j, k,
                          [&](Id, const CornerWords&, std::uint64_t active) { voxels += std::popcount(active); });
  return voxels;
}

// Step 3: each cut voxel's cube case and table entry (by its case and far
// bits, coarse_cases.hpp) found and the entry kept; every voxel row's
// coarse triangles counted (those with two equal corners dropped and the
// folds within each voxel decided: the table's) and its face triangles
// recorded, before any triangle is written. The one walk over the cut
// voxels before the write (the plain contour's count pass is not run: only
// its grid rows' counts, count_grid_rows); it also counts the fine
// triangles, which bound the output and are reported.
inline void tally_coarse_triangles(const InsideBits& bits, const GridShape& s, const CoarseBits& cb,
                                   CoarseTriangles& ct) {
  const Id layers = s.nz - 1, voxel_rows = (s.ny - 1) * layers;
  const VoxelBricks bricks(s, 0, layers);
  ct.size_for(static_cast<std::size_t>(bricks.count()), static_cast<std::size_t>(voxel_rows));
  const CoarseVoxelTable& table = coarse_voxel_table(s.reversed_axes);
  const auto& cubes = *s.table;
  parallel::for_each_dynamic(bricks.count(), [&](Id brick) {
    const Id kb = bricks.k_begin(brick), ke = bricks.k_end(brick), jb = bricks.j_begin(brick), je = bricks.j_end(brick);
    // Rows whose four grid rows have no cut edge have no cut voxel.
    auto has_cuts = [&](Id j, Id k) {
      const Id r = k * s.ny + j;
      return cb.cut[r] || cb.cut[r + 1] || cb.cut[r + s.ny] || cb.cut[r + s.ny + 1];
    };
    const Id voxels = count_cut_voxels(bits, s, bricks, brick, has_cuts);
    std::uint16_t* entry = ct.entries[brick].room_for(static_cast<std::size_t>(voxels));
    std::uint32_t* voxel_i = ct.voxel_i[brick].room_for(static_cast<std::size_t>(voxels));
    // Face triangles: room for one every two cut voxels at first (0.43 to
    // 0.48 a voxel on brainsmall, ch2better, the 256^3 sphere and smoothed
    // noise), grown (doubled, copied) when a word's voxels, five each at
    // most, might not fit, and kept for later calls.
    KeptArray<FaceTriangle>& faces = ct.faces[brick];
    std::size_t room = std::max<std::size_t>(faces.size, static_cast<std::size_t>(voxels / 2) + 64);
    FaceTriangle* base = faces.room_for(room);
    FaceTriangle* f = base;
    Id fine = 0;
    for (Id k = kb; k < ke; ++k)
      for (Id j = jb; j < je; ++j) {
        const Id vr = k * (s.ny - 1) + j;
        const std::uint16_t* const row_entries = entry;
        const std::size_t row_faces = static_cast<std::size_t>(f - base);
        std::uint32_t written = 0;  // triangles of the row so far
        if (has_cuts(j, k)) {
          const VoxelRowFar far(cb, s, j, k);
          for_each_cut_word(bits, s, j, k, [&](Id q, const CornerWords& w, std::uint64_t active) {
            // Room for the word's face triangles, five a voxel at most,
            // checked once a word.
            const std::size_t used = static_cast<std::size_t>(f - base),
                              most = used + 5 * static_cast<std::size_t>(std::popcount(active));
            if (most > room) {
              KeptArray<FaceTriangle> bigger;
              room = std::max(2 * room, most);
              std::memcpy(bigger.room_for(room), base, used * sizeof(FaceTriangle));
              faces = std::move(bigger);
              base = faces.data(), f = base + used;
            }
            std::uint8_t far_bytes[65];
            far.bytes_of_word(q, far_bytes);
            for_each_case_of_word(w, active, [&](int bit, unsigned cube_case) {
              const auto i = static_cast<std::uint32_t>(64 * q + bit);
              fine += cubes.triangle_count[cube_case];
              const std::uint16_t e = table.index(cube_case, VoxelRowFar::key(far_bytes, bit));
              *entry++ = e;
              *voxel_i++ = i;
              const CoarseVoxel v = table.entries[e];
              for (unsigned m = static_cast<unsigned>(v >> kCoarseFaceShift); m; m &= m - 1) {
                const int t = std::countr_zero(m);
                const unsigned c = static_cast<unsigned>(v >> (9 * t)) & 511u;
                *f++ = {written + static_cast<std::uint32_t>(t), i, table.face_code[c], 0};
              }
              written += static_cast<std::uint32_t>((v >> kCoarseCountShift) & 7u);
            });
          });
        }
        ct.voxels[vr] = static_cast<std::uint32_t>(entry - row_entries);
        ct.entry_first[vr] = static_cast<std::uint32_t>(row_entries - ct.entries[brick].data());
        ct.face_first[vr] = static_cast<std::uint32_t>(row_faces);
        ct.face_count[vr] = static_cast<std::uint32_t>(static_cast<std::size_t>(f - base) - row_faces);
        ct.first[vr] = written;
      }
    ct.fine[static_cast<std::size_t>(brick)] = fine;
  }, 1);
  ct.fine_triangles = 0;
  for (const Id n : ct.fine) ct.fine_triangles += n;
}

// Step 4: the folds across the faces between voxels decided (each row the
// faces it owns, coarse_folds.hpp), then each voxel row's kept triangles
// counted and its first triangle found by a prefix sum, starting at
// `first_triangle`. Sets ct.count.
inline void fold_and_count(const GridShape& s, Id first_triangle, CoarseTriangles& ct) {
  const Id layers = s.nz - 1, voxel_rows = (s.ny - 1) * layers;
  const VoxelBricks bricks(s, 0, layers);
  auto face_count = [&](Id vr) { return static_cast<std::size_t>(ct.face_count[vr]); };
  // ct.folded first marks the rows a fold may have touched (the deciding
  // row and the two next to it, which other rows decide at once: a relaxed
  // atomic store of 1), so that only those rows' records are counted.
  ct.folded.assign(static_cast<std::size_t>(voxel_rows), 0);
  auto may_have_folds = [&](Id vr) { std::atomic_ref<std::uint8_t>(ct.folded[vr]).store(1, std::memory_order_relaxed); };
  parallel::for_each_dynamic(voxel_rows, [&](Id vr) {
    const Id j = vr % (s.ny - 1), k = vr / (s.ny - 1);
    const Id ny_row = j + 1 < s.ny - 1 ? vr + 1 : -1, nz_row = k + 1 < layers ? vr + (s.ny - 1) : -1;
    const std::size_t n_own = face_count(vr), n_y = ny_row >= 0 ? face_count(ny_row) : 0,
                      n_z = nz_row >= 0 ? face_count(nz_row) : 0;
    if (n_own + n_y + n_z < 2) return;
    thread_local std::vector<FoldEntry> entries;
    if (!fold_across_faces(static_cast<std::size_t>(s.nx), ct.faces_of(bricks, s.ny, vr), n_own, j == 0, k == 0,
                           n_y ? ct.faces_of(bricks, s.ny, ny_row) : nullptr, n_y,
                           n_z ? ct.faces_of(bricks, s.ny, nz_row) : nullptr, n_z, entries))
      return;
    may_have_folds(vr);
    if (n_y) may_have_folds(ny_row);
    if (n_z) may_have_folds(nz_row);
  }, 64);
  parallel::for_each(voxel_rows, [&](Id vr) {
    if (!ct.folded[vr]) return;
    const FaceTriangle* f = ct.faces_of(bricks, s.ny, vr);
    Id dropped = 0;
    for (std::size_t e = 0; e < face_count(vr); ++e) dropped += f[e].folded;
    ct.first[vr] -= dropped;
    ct.folded[vr] = dropped > 0;
  });
  ct.first[voxel_rows] = 0;
  ct.count = parallel::exclusive_scan(ct.first.data(), ct.first.data(), voxel_rows + 1);
  if (first_triangle) parallel::for_each(voxel_rows + 1, [&](Id vr) { ct.first[vr] += first_triangle; });
}

// Step 8: the kept triangles of voxel rows (j, k), k in [0, nz - 1), with
// coarse ids, written once at their final place in `connectivity` (the
// rows' first triangles of fold_and_count), from the cut voxels the tally
// kept (no walk over the inside bits, no second lookup).
inline void write_coarse_triangles(const GridShape& s, const CoarseBits& cb, const CoarseTriangles& ct,
                                   PointIndex* connectivity) {
  const VoxelBricks bricks(s, 0, s.nz - 1);
  const CoarseVoxel* table = coarse_voxel_table(s.reversed_axes).entries.data();
  parallel::for_each_dynamic(bricks.count(), [&](Id brick) {
    // Coarse ids by grid point of the brick's grid rows j in [j_begin,
    // j_end] of two planes: plane k + 1's rows become plane k's for the
    // next layer, so each row is filled once per brick.
    const Id j_begin = bricks.j_begin(brick), rows_j = bricks.j_end(brick) - j_begin + 1;
    thread_local std::vector<std::uint32_t> id_scratch;
    if (static_cast<Id>(id_scratch.size()) < 2 * rows_j * s.nx)
      id_scratch.resize(static_cast<std::size_t>(2 * rows_j * s.nx));
    auto ids_of = [&](int plane, Id j) { return id_scratch.data() + (plane * rows_j + (j - j_begin)) * s.nx; };
    // The tally's cut voxels, in its order.
    const std::uint16_t* entry = ct.entries[brick].data();
    const std::uint32_t* voxel_i = ct.voxel_i[brick].data();
    int lo = 0;  // the plane of layer k's lower grid rows
    for (Id j = j_begin; j < j_begin + rows_j; ++j) cb.row_ids(bricks.k_begin(brick) * s.ny + j, ids_of(lo, j));
    for (Id k = bricks.k_begin(brick); k < bricks.k_end(brick); ++k) {
      const int hi = lo ^ 1;
      for (Id j = j_begin; j < j_begin + rows_j; ++j) cb.row_ids((k + 1) * s.ny + j, ids_of(hi, j));
      for (Id j = j_begin; j < bricks.j_end(brick); ++j) {
        // Corner c (x | y << 1 | z << 2) of voxel i is grid point i + (c & 1)
        // of corner row c >> 1 (rows by y | z << 1): its id at ids[i +
        // offset[c]], offsets from the voxel row's first corner row.
        const std::uint32_t* const ids = ids_of(lo, j);
        const Id dz = ids_of(hi, j) - ids;
        const Id offset[8] = {0, 1, s.nx, s.nx + 1, dz, dz + 1, dz + s.nx, dz + s.nx + 1};
        const Id vr = k * (s.ny - 1) + j;
        PointIndex* o = connectivity + 3 * ct.first[vr];
        // Triangle corners c0 | c1 << 3 | c2 << 6 (the low 9 bits of c) of
        // the voxel whose corner 0 has its id at `at`, as coarse ids.
        auto write = [&](const std::uint32_t* at, std::uint64_t c) {
          o[0] = at[offset[c & 7u]], o[1] = at[offset[(c >> 3) & 7u]], o[2] = at[offset[(c >> 6) & 7u]];
          o += 3;
        };
        const std::uint32_t* const row_end = voxel_i + ct.voxels[vr];
        if (!ct.folded[vr]) {
          // The entry's triangles nine bits at a time (a shift by 9 t a
          // triangle was a multiply and a variable shift).
          for (; voxel_i < row_end; ++voxel_i) {
            const CoarseVoxel v = table[*entry++];
            const std::uint32_t* const at = ids + *voxel_i;
            std::uint64_t c = v;
            for (auto t = static_cast<unsigned>(v >> kCoarseCountShift) & 7u; t; --t, c >>= 9) write(at, c);
          }
        } else {
          // A row with folds across faces (few): its dropped triangles, in
          // the order of its face records, skipped.
          const FaceTriangle* f = ct.faces_of(bricks, s.ny, vr);
          const FaceTriangle* const f_end = f + ct.face_count[vr];
          auto next_drop = [&] {
            while (f < f_end && !f->folded) ++f;
            return f < f_end ? f++->tri : ~std::uint32_t{0};
          };
          std::uint32_t drop = next_drop(), written = 0;
          for (; voxel_i < row_end; ++voxel_i) {
            const CoarseVoxel v = table[*entry++];
            const int count = static_cast<int>((v >> kCoarseCountShift) & 7u);
            for (int t = 0; t < count; ++t, ++written) {
              if (written == drop) drop = next_drop();
              else write(ids + *voxel_i, v >> (9 * t));
            }
          }
        }
      }
      lo = hi;
    }
  }, 1);
}

}  // namespace keymesh::generate
