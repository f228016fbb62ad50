#pragma once
// A coarse point's fan, read from the voxels around it (coarse_fans.hpp):
// each voxel's share of it, tabulated by the voxel's coarse table entry
// (coarse_cases.hpp) and the corner the point is of it.
//
// A coarse triangle (v, a, b), counter-clockwise from v, contributes the
// link edge a -> b to v's fan; v is one closed fan (split_nonmanifold's
// one_closed_fan) when its link edges form one directed cycle through
// distinct points, at least three. v's triangles are those of the eight
// voxels having v as a corner; inside one voxel its link edges join corners
// of that voxel. A voxel's share is summarised as one chain (a path of link
// edges, or a closed cycle) with its first and last corner and the corners
// it leaves from; anything else (two chains, a corner left twice, a
// triangle repeating v) is "tangled" and makes v a suspect.
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <memory>

#include "coarse_cases.hpp"

namespace keymesh::generate {

// One voxel's share of the fan of its corner c, corners named by a ^ c (so
// 1-7; 0 would be c itself):
//  bits 0-7    the corners a link edge leaves from (bit a ^ c; bit 0 never)
//  bits 8-10   the chain's first corner, bits 11-13 its last (equal: closed)
//  bits 14-15  kNoFan (no triangle at c), kOneChain or kTangled
// The corners a link edge arrives at are then the leaving ones without the
// first, with the last.
using CornerChain = std::uint16_t;
enum ChainKind : unsigned { kNoFan = 0, kOneChain = 1, kTangled = 2 };
constexpr int kChainKindShift = 14;

// The shares at its eight corners of a voxel whose coarse triangles are
// `v`'s but those with a bit in `dropped` (bit t: triangle t, dropped by a
// fold across a face).
void corner_chains(CoarseVoxel v, unsigned dropped, CornerChain chains[8]);

// The 27 grid points around a coarse point, i + 3 j + 9 k for offsets
// i, j, k + 1 in {0, 1, 2} (13: the point itself): around[c][a ^ c] is
// corner a of a voxel of which the point is corner c, and spread[c][m] the
// corners in m (bits a ^ c) as a set of its 26 neighbours (bit n, or n - 1
// past the point itself).
constexpr unsigned kFanCentre = 13;
struct FanNeighbours {
  std::uint8_t around[8][8] = {};
  std::uint32_t spread[8][256] = {};

  constexpr FanNeighbours() {
    for (unsigned c = 0; c < 8; ++c) {
      for (unsigned l = 0; l < 8; ++l) {
        const unsigned a = l ^ c;
        unsigned index = 0, weight = 1;
        for (unsigned axis = 0; axis < 3; ++axis, weight *= 3)
          index += (((a >> axis) & 1u) + 1u - ((c >> axis) & 1u)) * weight;
        around[c][l] = static_cast<std::uint8_t>(index);
      }
      for (unsigned m = 0; m < 256; ++m)
        for (unsigned l = 1; l < 8; ++l)
          if ((m >> l) & 1u) spread[c][m] |= 1u << (around[c][l] - (around[c][l] > kFanCentre ? 1u : 0u));
    }
  }
};
inline constexpr FanNeighbours kFanNeighbours{};

// A voxel's share moved to the point's neighbourhood, as the check adds it:
//  bits 0-25   the neighbours a link edge leaves from (all when tangled)
//  bits 26-51  the neighbours a link edge arrives at (none when tangled)
//  bits 52-56  the chain's first neighbour (by around's index), bits 57-61
//              its last (13 for both without a chain: the check writes
//              there and never reads it)
// Two shares with no neighbour in common add up to their union: the check
// sums them and compares with their union instead of testing each pair.
using FanShare = std::uint64_t;
constexpr std::uint64_t kNeighbourBits = (std::uint64_t{1} << 26) - 1;
constexpr std::uint64_t kShareSets = (std::uint64_t{1} << 52) - 1;
constexpr int kShareFirst = 52, kShareLast = 57;
FanShare fan_share(CornerChain chain, unsigned c);

// A voxel's share at the point's 18 ports (its face and edge neighbours,
// the only neighbours two voxels share), for the quick test that clears
// most points before any walk (coarse_fans.hpp):
//  bits 0-5    weight: 1 for a path whose ends are ports; 6 for anything
//              else (a closed chain, an end at a corner neighbour, tangled)
//  bits 6-17   the wall (kWalls) holding both ends of the path, if any
//  bits 18-35  the ports a link edge leaves from, bits 36-53 arrives at
//              (a corner neighbour is then inside the path: left and
//              arrived at by it alone, so it never decides the test)
//  0 without a triangle at the corner; bits 54-63 stay 0, so that eight
// shares add up without a carry past bit 63.
// The eight shares' weights add up to at most 5, they share no bit (their
// sum is their union above the weight) and the ports left are those arrived
// at: then the point is one closed fan. Its link is paths between ports,
// each in its own voxel, a port left by one and arrived at by one, so the
// paths join into cycles; a cycle of two paths needs two voxels with both
// ends in their common wall (voxels sharing two ports share a wall: its two
// face neighbours and its edge neighbour), which sets that wall's bit twice;
// so every cycle has three paths or more, and five paths are one cycle.
using PortShare = std::uint64_t;
constexpr int kPortWallShift = 6, kPortLeavingShift = 18, kPortArrivingShift = 36;
constexpr PortShare kPortWeight = 63, kPortIrregular = 6;
// The internal walls of the point's eight voxels: the wall across axis a
// between voxel o and o ^ (1 << a) is 4 a + o's other two bits.
constexpr unsigned kWalls = 12;
PortShare port_share(CornerChain chain, unsigned c);

// fan_share(corner_chains(entries[e], 0)[c], c) and port_share's for every
// CoarseVoxelTable entry e and corner c, each entry's worked out when first asked for:
// a volume meets a few thousand of the 36,450 entries, and working them all
// out cost 32 M instructions, more than the whole check on a small volume,
// in every process. Asked for from any thread: a share is the same whoever
// works it out, so two threads storing it at once store the same bits (and
// both then set its ready byte, released after the shares).
class CoarseFanTable {
 public:
  explicit CoarseFanTable(const CoarseVoxelTable& voxels);

  // Makes sure entry's shares are worked out (once a cut voxel, before its
  // corners' points ask for them), and starts loading its shares at the
  // ports, which those points read next. Whether an entry is worked out is
  // a byte of its own (36 KB for all): finding out from the shares loaded
  // the line the walk reads, which most points never do, and left the
  // ports' line to miss in the check.
  [[gnu::always_inline]] void prepare(std::uint16_t entry) const {
    if (!std::atomic_ref<std::uint8_t>(ready_[entry]).load(std::memory_order_acquire)) work_out(entry);
    __builtin_prefetch(port_shares_.get() + 8 * std::size_t{entry});
  }
  // The same for n entries (a voxel row's cut voxels), each also stored in
  // row[at[v]] (the row's entries by voxel), in one loop: the tables'
  // addresses read once.
  void prepare(const std::uint16_t* entries, const std::uint32_t* at, std::uint32_t n, std::uint16_t* row) const {
    std::uint8_t* const ready = ready_.get();
    const PortShare* const ports = port_shares_.get();
    for (std::uint32_t v = 0; v < n; ++v) {
      const std::uint16_t e = entries[v];
      row[at[v]] = e;
      if (!std::atomic_ref<std::uint8_t>(ready[e]).load(std::memory_order_acquire)) work_out(e);
      __builtin_prefetch(ports + 8 * std::size_t{e});
    }
  }
  // A prepared entry's share at corner c.
  [[gnu::always_inline]] FanShare share(std::uint16_t entry, unsigned c) const {
    return std::atomic_ref<FanShare>(shares_[8 * std::size_t{entry} + c]).load(std::memory_order_relaxed);
  }
  // Its share at the ports (port_share above), in a table of its own, so that the
  // quick test reads 64 bytes an entry, as the walk does.
  [[gnu::always_inline]] PortShare share_at_ports(std::uint16_t entry, unsigned c) const {
    return std::atomic_ref<PortShare>(port_shares_[8 * std::size_t{entry} + c]).load(std::memory_order_relaxed);
  }

 private:
  void work_out(std::uint16_t entry) const;

  // Zero pages until written (calloc): only the entries met are touched.
  struct Free {
    void operator()(void* p) const { std::free(p); }
  };
  std::unique_ptr<FanShare[], Free> shares_;
  std::unique_ptr<PortShare[], Free> port_shares_;
  std::unique_ptr<std::uint8_t[], Free> ready_;  // 1 once the entry's shares are stored
  const CoarseVoxelTable* voxels_;
};

// Made once (thread-safe static initialisation), over
// coarse_voxel_table(reversed_axes).
const CoarseFanTable& coarse_fan_table(bool reversed_axes = false);

}  // namespace keymesh::generate
