#pragma once
// Which coarse points have no triangle, and which may not be one closed fan,
// found from the voxels around each point before any triangle is written
// (contour_coarse_rows.hpp, between the folds and the numbering).
//
// A coarse point's triangles all come from the eight voxels it is a corner
// of (a coarse triangle joins three corners of its voxel), and each voxel's
// share of the point's fan is a lookup by its table entry and the corner
// (coarse_fan_table.hpp). The eight shares, moved to the point's
// neighbourhood (the 27 grid points around it, 13 being itself), make one
// closed fan when: no share is tangled, no neighbour is left or arrived at
// twice, the neighbours left are those arrived at, there are three or more,
// and the chains join into one cycle. That is exactly when the point's link
// edges form one cycle, except that a fan passing twice through one voxel
// is called tangled: such points are suspects, a few more than
// split_nonmanifold needs to look at (it checks each against the triangles
// again). Most points are cleared before that walk by a quick test on
// their shares at the ports (fan_verdict). A point with no share at all
// has no triangle: it is not numbered, so the output has no unused point
// and nothing is renumbered afterwards.
// Voxels that lost triangles to a fold across a face (few) have their share
// worked out from what is left.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "coarse_fan_table.hpp"
#include "contour_coarse_rows.hpp"
#include "keymesh/generate/coarsen/split_nonmanifold.hpp"

namespace keymesh::generate {

// The shares of one point's fan, added voxel by voxel.
class FanShares {
 public:
  [[gnu::always_inline]] void add(FanShare share) {
    sum_ += share & kShareSets, union_ |= share;
    const auto first = static_cast<unsigned>((share >> kShareFirst) & 31u);
    by_first_[first] = share;  // a share without a chain: the point's own slot, never read
    start_ = share & kNeighbourBits ? first : start_;
  }

  bool empty() const { return (union_ & kShareSets) == 0; }

  bool one_closed_fan() const {
    const std::uint64_t sets = union_ & kShareSets, leaving = sets & kNeighbourBits, arriving = sets >> 26;
    // No neighbour left or arrived at twice, those left are those arrived
    // at (a tangled share arrives nowhere), three or more.
    if (sum_ != sets || leaving != arriving || std::popcount(leaving) < 3) return false;
    // Each chain's last neighbour is another chain's first (a neighbour
    // arrived at is left, by exactly one chain, which did not arrive there):
    // one cycle when the walk from a chain's first comes back having left
    // every neighbour.
    unsigned at = start_;
    std::uint64_t left = 0;
    for (int chains = 0; chains < 8; ++chains) {
      const FanShare chain = by_first_[at];
      left |= chain & kNeighbourBits;
      at = static_cast<unsigned>(chain >> kShareLast) & 31u;
      if (at == start_) break;
    }
    return at == start_ && left == leaving;
  }

 private:
  std::uint64_t sum_ = 0, union_ = 0;
  unsigned start_ = kFanCentre;
  FanShare by_first_[32];  // by a 5-bit index: 27 neighbours and room
};

// What the check makes of a coarse candidate.
enum class FanVerdict { kNoTriangle, kOneClosedFan, kSuspect };

// The walk, out of line: the quick test's registers are not kept for it.
template <class ShareAt>
[[gnu::noinline]] FanVerdict walked_fan_verdict(ShareAt share) {
  FanShares fan;
  [&]<unsigned... o>(std::integer_sequence<unsigned, o...>) {
    (fan.add(share(o)), ...);
  }(std::make_integer_sequence<unsigned, 8>{});
  return fan.one_closed_fan() ? FanVerdict::kOneClosedFan : FanVerdict::kSuspect;
}

// The verdict on a point from its eight voxels' shares, port(o) and
// share(o) for voxel o = dx | dy << 1 | dz << 2 (the point is its corner
// 7 - o): first the quick test on the shares at the ports
// (coarse_fan_table.hpp: PortShare), which clears most points with eight
// loads and adds; the walk over the whole shares (FanShares) for the rest
// (one point in six on ch2better: six or more paths, a closed chain, an end
// at a corner neighbour, two paths with their ends in one wall). The quick
// test clears only points the walk clears, so the verdict is the walk's.
template <class PortAt, class ShareAt>
[[gnu::always_inline]] inline FanVerdict fan_verdict(PortAt port, ShareAt share) {
  PortShare sum = 0, all = 0;
  [&]<unsigned... o>(std::integer_sequence<unsigned, o...>) {
    (
        [&] {
          const PortShare p = port(o);  // one load (the table's loads are atomic: never merged)
          sum += p, all |= p;
        }(),
        ...);
  }(std::make_integer_sequence<unsigned, 8>{});
  if (all == 0) return FanVerdict::kNoTriangle;
  constexpr PortShare kPorts = (PortShare{1} << 18) - 1;
  const PortShare paths = sum & kPortWeight;
  if (paths - 3 <= 2 && (sum >> kPortWallShift) == (all >> kPortWallShift) &&
      ((all >> kPortLeavingShift) & kPorts) == all >> kPortArrivingShift)
    return FanVerdict::kOneClosedFan;
  return walked_fan_verdict(share);
}

// A coarse candidate the check could not clear: grid row r, point i.
struct FanSuspect {
  Id row;
  Id i;
};

// Every brick's suspects, in its rows' order (kept by the caller), and how
// many copies of points the split can make of them: a point with d
// corners has at most d fans and keeps one (split_nonmanifold.hpp; its
// copies' corners are its own), so that the caller can leave room for them.
struct CoarseFans {
  std::vector<std::vector<FanSuspect>> suspects;
  std::vector<Id> copies;  // by brick, at most

  Id most_copies() const {
    Id total = 0;
    for (Id c : copies) total += c;
    return total;
  }
};

// The corners at its corner c of a voxel's table entry's triangles (those a
// fold across a face dropped still counted: a bound).
inline unsigned corners_at(CoarseVoxel v, unsigned c) {
  const auto count = static_cast<unsigned>((v >> kCoarseCountShift) & 7u);
  unsigned at = 0;
  for (unsigned t = 0; t < count; ++t) {
    const auto x = static_cast<unsigned>(v >> (9 * t));
    at += ((x & 7u) == c) + (((x >> 3) & 7u) == c) + (((x >> 6) & 7u) == c);
  }
  return at;
}

// The table entries of a window of voxel rows around one brick's point
// rows, by voxel i + 1 (slots 0 and nx hold entry 0, no triangle, so that a
// point's voxels i - 1 and i are read without a test at the row's ends),
// and, for rows that lost triangles to a fold across a face, the shares of
// each voxel that lost some, worked out once from what is left (a voxel is
// read by the eight points at its corners). In the calling thread's scratch.
class FanWindow {
  struct DroppedShare {
    FanShare whole;
    PortShare ports;
  };

 public:
  FanWindow(const GridShape& s, const CoarseTriangles& ct, const VoxelBricks& bricks, Id brick)
      : nx_(s.nx), ny_(s.ny), layers_(s.nz - 1), j0_(bricks.j_begin(brick) - 1), k0_(bricks.k_begin(brick) - 1),
        rows_j_(bricks.j_end(brick) - j0_), rows_k_(bricks.k_end(brick) - k0_) {
    thread_local std::vector<std::uint16_t> entry_scratch;
    thread_local std::vector<std::uint32_t> dropped_scratch;
    thread_local std::vector<DroppedShare> share_scratch;
    thread_local std::vector<const std::uint16_t*> row_scratch;
    thread_local std::vector<const std::uint32_t*> dropped_row_scratch;
    const auto width = static_cast<std::size_t>(nx_ + 1), slots = static_cast<std::size_t>(rows_j_ * rows_k_ + 1);
    if (entry_scratch.size() < slots * width) entry_scratch.resize(slots * width), dropped_scratch.resize(slots * width);
    row_scratch.assign(slots, nullptr), dropped_row_scratch.assign(slots, nullptr);
    rows_ = row_scratch.data(), dropped_rows_ = dropped_row_scratch.data();
    share_scratch.clear();
    shares_ = &share_scratch;
    // Rows without a cut voxel (and those past the grid) read one row of
    // entry 0, no triangle, cleared once.
    std::uint16_t* const zeros = entry_scratch.data() + none() * width;
    std::memset(zeros, 0, sizeof(std::uint16_t) * width);
    std::fill(rows_, rows_ + slots, zeros);
    const CoarseFanTable& table = coarse_fan_table(s.reversed_axes);
    const CoarseVoxel* voxels = coarse_voxel_table(s.reversed_axes).entries.data();
    for (Id k = std::max<Id>(k0_, 0); k < k0_ + rows_k_; ++k)
      for (Id j = std::max<Id>(j0_, 0); j < j0_ + rows_j_; ++j) {
        const Id slot = (k - k0_) * rows_j_ + (j - j0_), vr = k * (ny_ - 1) + j, b = bricks.brick_of(j, k);
        const std::uint32_t n = ct.voxels[vr];
        if (n == 0) continue;
        std::uint16_t* row = entry_scratch.data() + slot * width;
        std::memset(row, 0, sizeof(std::uint16_t) * width);  // entry 0: no triangle
        rows_[slot] = row;
        const std::uint16_t* const entry = ct.entries[b].data() + ct.entry_first[vr];
        const std::uint32_t* const voxel_i = ct.voxel_i[b].data() + ct.entry_first[vr];
        table.prepare(entry, voxel_i, n, row + 1);
        if (!ct.folded[vr]) continue;
        // The dropped face triangles, by voxel: the records follow the
        // row's triangle order, as the voxels do.
        std::uint32_t* dropped = dropped_scratch.data() + slot * width;
        std::memset(dropped, 0, sizeof(std::uint32_t) * width);
        dropped_rows_[slot] = dropped;
        const FaceTriangle* f = ct.faces_of(bricks, ny_, vr);
        const FaceTriangle* const f_end = f + ct.face_count[vr];
        std::uint32_t before = 0;  // the row's triangles before voxel v's
        for (std::uint32_t v = 0; v < n && f < f_end; ++v) {
          const auto count = static_cast<std::uint32_t>((voxels[entry[v]] >> kCoarseCountShift) & 7u);
          unsigned lost = 0;  // bit t: the voxel's triangle t
          for (; f < f_end && f->tri < before + count; ++f)
            if (f->folded) lost |= 1u << (f->tri - before);
          before += count;
          if (!lost) continue;
          CornerChain left[8];
          corner_chains(voxels[entry[v]], lost, left);
          for (unsigned c = 0; c < 8; ++c) shares_->push_back({fan_share(left[c], c), port_share(left[c], c)});
          dropped[voxel_i[v] + 1] = static_cast<std::uint32_t>(shares_->size() / 8);
        }
      }
    table.prepare(0);
  }

  // The rows of voxel row (j, k): entries, and which voxels lost triangles
  // (null when none did; else 0, or 1 + the voxel's index for dropped_share).
  const std::uint16_t* entries(Id j, Id k) const { return rows_[slot(j, k)]; }
  const std::uint32_t* dropped(Id j, Id k) const { return dropped_rows_[slot(j, k)]; }
  // A voxel that lost triangles: its share at corner c, whole and at the ports.
  FanShare dropped_share(std::uint32_t at, unsigned c) const { return (*shares_)[8 * (at - 1) + c].whole; }
  PortShare dropped_port_share(std::uint32_t at, unsigned c) const { return (*shares_)[8 * (at - 1) + c].ports; }

 private:
  Id none() const { return rows_j_ * rows_k_; }
  Id slot(Id j, Id k) const {
    return j < 0 || k < 0 || j >= ny_ - 1 || k >= layers_ ? none() : (k - k0_) * rows_j_ + (j - j0_);
  }

  Id nx_, ny_, layers_, j0_, k0_, rows_j_, rows_k_;
  const std::uint16_t** rows_;           // by slot; the last (none()) for rows past the grid
  const std::uint32_t** dropped_rows_;   // by slot; null where no voxel lost triangles
  std::vector<DroppedShare>* shares_;
};

// Checks every coarse candidate of cb.points (mark_coarse_points' bits)
// from its voxels' table entries: clears the bits of those without a
// triangle and lists, by brick, those that may not be one closed fan (and
// the most copies the split can make of them). Each
// brick checks the points of its grid rows (and of the grid's last row and
// plane, for the bricks along them), so each point once.
inline void check_coarse_fans(const GridShape& s, const CoarseTriangles& ct, CoarseBits& cb, CoarseFans& fans) {
  const Id layers = s.nz - 1, wpr = cb.words_per_row;
  const VoxelBricks bricks(s, 0, layers);
  fans.suspects.resize(static_cast<std::size_t>(bricks.count()));
  fans.copies.assign(static_cast<std::size_t>(bricks.count()), 0);
  const CoarseFanTable& table = coarse_fan_table(s.reversed_axes);
  const CoarseVoxel* const voxels = coarse_voxel_table(s.reversed_axes).entries.data();
  parallel::for_each_dynamic(bricks.count(), [&](Id brick) {
    std::vector<FanSuspect>& suspects = fans.suspects[static_cast<std::size_t>(brick)];
    suspects.clear();
    Id copies = 0;
    const FanWindow window(s, ct, bricks, brick);
    const Id j_end = bricks.j_end(brick) == s.ny - 1 ? s.ny : bricks.j_end(brick);
    const Id k_end = bricks.k_end(brick) == layers ? s.nz : bricks.k_end(brick);
    for (Id k = bricks.k_begin(brick); k < k_end; ++k)
      for (Id j = bricks.j_begin(brick); j < j_end; ++j) {
        const Id r = k * s.ny + j;
        if (!cb.live[r]) continue;
        // Voxel rows (j - 1 + dy, k - 1 + dz) at index dy | dz << 1.
        const std::uint16_t* rows[4] = {window.entries(j - 1, k - 1), window.entries(j, k - 1),
                                        window.entries(j - 1, k), window.entries(j, k)};
        const std::uint32_t* dropped[4] = {window.dropped(j - 1, k - 1), window.dropped(j, k - 1),
                                           window.dropped(j - 1, k), window.dropped(j, k)};
        const bool any_dropped = dropped[0] || dropped[1] || dropped[2] || dropped[3];
        std::uint64_t* words = cb.point_words(r);
        // The point is corner c = 7 - o of its voxel o = dx | dy << 1 | dz << 2.
        auto verdict = [&](Id i) {
          auto entry = [&](unsigned o) { return rows[o >> 1][i + (o & 1u)]; };
          auto at = [&](unsigned o) { return dropped[o >> 1] ? dropped[o >> 1][i + (o & 1u)] : 0u; };
          if (any_dropped && (at(0) | at(1) | at(2) | at(3) | at(4) | at(5) | at(6) | at(7)))
            return fan_verdict(
                [&](unsigned o) { return at(o) ? window.dropped_port_share(at(o), 7u - o) : table.share_at_ports(entry(o), 7u - o); },
                [&](unsigned o) { return at(o) ? window.dropped_share(at(o), 7u - o) : table.share(entry(o), 7u - o); });
          return fan_verdict([&](unsigned o) { return table.share_at_ports(entry(o), 7u - o); },
                             [&](unsigned o) { return table.share(entry(o), 7u - o); });
        };
        for (Id q = 0; q < wpr; ++q)
          for (std::uint64_t m = words[q]; m; m &= m - 1) {
            const Id i = 64 * q + std::countr_zero(m);
            const FanVerdict v = verdict(i);
            if (v == FanVerdict::kNoTriangle) {
              words[q] &= ~(std::uint64_t{1} << (i % 64));
            } else if (v == FanVerdict::kSuspect) {
              suspects.push_back({r, i});
              Id corners = 0;
              for (unsigned o = 0; o < 8; ++o) corners += corners_at(voxels[rows[o >> 1][i + (o & 1u)]], 7u - o);
              copies += corners - 1;
            }
          }
      }
    fans.copies[static_cast<std::size_t>(brick)] = copies;
  }, 1);
}

// The suspects' coarse ids (after number_coarse_points), ascending.
inline std::vector<PointIndex> suspect_ids(const CoarseFans& fans, const CoarseBits& cb) {
  std::vector<PointIndex> ids;
  for (const auto& brick : fans.suspects)
    for (const FanSuspect& p : brick) {
      const Id q = p.i / 64;
      const std::uint64_t below = (std::uint64_t{1} << (p.i % 64)) - 1;
      ids.push_back(static_cast<PointIndex>(cb.first_ids(p.row)[q] + std::popcount(cb.point_words(p.row)[q] & below)));
    }
  std::sort(ids.begin(), ids.end());
  return ids;
}

// The triangles of the voxel rows around the suspects (a point's triangles
// come from the four voxel rows around its grid row), appended to `ranges`
// in increasing order, rows next to each other joined: the rows are marked,
// then read in order (a range a row and a sort cost more).
inline void suspect_triangles(const GridShape& s, const CoarseFans& fans, const CoarseTriangles& ct,
                              std::vector<TriangleRange>& ranges) {
  const Id voxel_rows = (s.ny - 1) * (s.nz - 1);
  std::vector<std::uint64_t> marked(static_cast<std::size_t>(voxel_rows / 64 + 1), 0);
  for (const auto& brick : fans.suspects)
    for (const FanSuspect& p : brick) {
      const Id j = p.row % s.ny, k = p.row / s.ny;
      for (Id vk = std::max<Id>(k - 1, 0); vk <= std::min(k, s.nz - 2); ++vk)
        for (Id vj = std::max<Id>(j - 1, 0); vj <= std::min(j, s.ny - 2); ++vj) {
          const Id vr = vk * (s.ny - 1) + vj;
          marked[static_cast<std::size_t>(vr / 64)] |= std::uint64_t{1} << (vr % 64);
        }
    }
  const std::size_t before = ranges.size();
  for (std::size_t w = 0; w < marked.size(); ++w)
    for (std::uint64_t m = marked[w]; m; m &= m - 1) {
      const Id vr = static_cast<Id>(64 * w) + std::countr_zero(m);
      const TriangleRange r{ct.first[vr], ct.first[vr + 1]};
      if (r.end <= r.begin) continue;
      if (ranges.size() > before && ranges.back().end == r.begin) ranges.back().end = r.end;
      else ranges.push_back(r);
    }
}

// Sorted, overlapping and touching ranges joined, empty ones dropped.
inline void merge_ranges(std::vector<TriangleRange>& ranges) {
  std::sort(ranges.begin(), ranges.end(), [](const TriangleRange& a, const TriangleRange& b) { return a.begin < b.begin; });
  std::size_t out = 0;
  for (const TriangleRange& r : ranges) {
    if (r.end <= r.begin) continue;
    if (out > 0 && r.begin <= ranges[out - 1].end) ranges[out - 1].end = std::max(ranges[out - 1].end, r.end);
    else ranges[out++] = r;
  }
  ranges.resize(out);
}

}  // namespace keymesh::generate
