#include "coarse_fan_table.hpp"

#include <bit>
#include <new>
#include <stdexcept>

namespace keymesh::generate {

void corner_chains(CoarseVoxel v, unsigned dropped, CornerChain chains[8]) {
  const int count = static_cast<int>((v >> kCoarseCountShift) & 7u);
  // By corner c: the corners (as a ^ c) its link edges leave from and
  // arrive at, and where each leads.
  unsigned leaving[8] = {}, arriving[8] = {}, edges[8] = {};
  std::uint8_t next[8][8];
  bool tangled[8] = {};
  for (int t = 0; t < count; ++t) {
    if ((dropped >> t) & 1u) continue;
    const unsigned x = static_cast<unsigned>(v >> (9 * t)) & 511u;
    const unsigned corner[3] = {x & 7u, (x >> 3) & 7u, x >> 6};
    for (int k = 0; k < 3; ++k) {
      // The triangle seen from corner[k]: the link edge a -> b.
      const unsigned c = corner[k], a = corner[(k + 1) % 3] ^ c, b = corner[(k + 2) % 3] ^ c;
      tangled[c] = tangled[c] || a == 0 || b == 0 || ((leaving[c] >> a) & 1u) || ((arriving[c] >> b) & 1u);
      leaving[c] |= 1u << a, arriving[c] |= 1u << b;
      next[c][a] = static_cast<std::uint8_t>(b);
      ++edges[c];
    }
  }
  for (unsigned c = 0; c < 8; ++c) {
    chains[c] = 0;
    if (edges[c] == 0) continue;
    const CornerChain tangle = static_cast<CornerChain>(kTangled << kChainKindShift);
    // One start (a path) or none (every corner left is arrived at: a cycle).
    const unsigned starts = leaving[c] & ~arriving[c];
    if (tangled[c] || std::popcount(starts) > 1) {
      chains[c] = tangle;
      continue;
    }
    const unsigned first = static_cast<unsigned>(std::countr_zero(starts ? starts : leaving[c]));
    unsigned last = first, steps = 0;
    while (steps < edges[c]) {
      last = next[c][last], ++steps;
      if (last == first || !((leaving[c] >> last) & 1u)) break;
    }
    // All edges walked, ending where none leaves (a path) or back at the first.
    const bool one = steps == edges[c] && (starts ? !((leaving[c] >> last) & 1u) : last == first);
    chains[c] = one ? static_cast<CornerChain>(kOneChain << kChainKindShift | last << 11 | first << 8 | leaving[c])
                    : tangle;
  }
}

FanShare fan_share(CornerChain chain, unsigned c) {
  const unsigned kind = chain >> kChainKindShift, first = (chain >> 8) & 7u, last = (chain >> 11) & 7u;
  const unsigned leaving = chain & 255u;
  constexpr FanShare kNoChain = FanShare{kFanCentre} << kShareFirst | FanShare{kFanCentre} << kShareLast;
  if (kind == kNoFan) return kNoChain;
  if (kind == kTangled) return kNoChain | kNeighbourBits;
  const unsigned arriving = (leaving & ~(1u << first)) | (1u << last);
  const auto& n = kFanNeighbours;
  return FanShare{n.spread[c][leaving]} | FanShare{n.spread[c][arriving]} << 26 |
         FanShare{n.around[c][first]} << kShareFirst | FanShare{n.around[c][last]} << kShareLast;
}

namespace {

// spread[c][m]: the local codes in m (bits a ^ c) that are ports (one or
// two bits: face and edge neighbours), as a set of the 18 ports, numbered
// in around's order without the centre and the corner neighbours.
struct PortSets {
  std::uint32_t spread[8][256] = {};

  constexpr PortSets() {
    std::uint8_t port_of[27] = {};
    for (unsigned n = 0, next = 0; n < 27; ++n) {
      const unsigned off_axis = (n % 3 != 1) + (n / 3 % 3 != 1) + (n / 9 != 1);
      port_of[n] = static_cast<std::uint8_t>(off_axis == 1 || off_axis == 2 ? next++ : 255);
    }
    for (unsigned c = 0; c < 8; ++c)
      for (unsigned m = 0; m < 256; ++m)
        for (unsigned x = 1; x < 7; ++x)  // 7: the corner neighbour
          if ((m >> x) & 1u) spread[c][m] |= 1u << port_of[kFanNeighbours.around[c][x]];
  }
};
constexpr PortSets kPortSets{};

}  // namespace

PortShare port_share(CornerChain chain, unsigned c) {
  const unsigned kind = chain >> kChainKindShift, first = (chain >> 8) & 7u, last = (chain >> 11) & 7u;
  if (kind == kNoFan) return 0;
  // Codes with one or two bits are ports; seven is the corner neighbour,
  // which no other voxel has.
  if (kind == kTangled || first == last || first == 7u || last == 7u) return kPortIrregular;
  const unsigned leaving = chain & 255u, arriving = (leaving & ~(1u << first)) | (1u << last);
  PortShare s = 1 | PortShare{kPortSets.spread[c][leaving]} << kPortLeavingShift |
                PortShare{kPortSets.spread[c][arriving]} << kPortArrivingShift;
  // Both ends in the wall across axis a: neither end is a step along a.
  const unsigned o = 7u - c;
  for (unsigned a = 0; a < 3; ++a)
    if (!(((first | last) >> a) & 1u)) {
      const unsigned others = a == 0 ? o >> 1 : a == 1 ? (o & 1u) | (o >> 2) << 1 : o & 3u;
      s |= PortShare{1} << (kPortWallShift + 4 * a + others);
    }
  return s;
}

CoarseFanTable::CoarseFanTable(const CoarseVoxelTable& voxels) : voxels_(&voxels) {
  if (voxels.first[0] != 0 || ((voxels.entries[0] >> kCoarseCountShift) & 7u) != 0)
    throw std::logic_error("coarse_fan_table: entry 0 is not the voxel without triangles");
  shares_.reset(static_cast<FanShare*>(std::calloc(8 * voxels.entries.size(), sizeof(FanShare))));
  port_shares_.reset(static_cast<PortShare*>(std::calloc(8 * voxels.entries.size(), sizeof(PortShare))));
  ready_.reset(static_cast<std::uint8_t*>(std::calloc(voxels.entries.size(), 1)));
  if (!shares_ || !port_shares_ || !ready_) throw std::bad_alloc();
}

void CoarseFanTable::work_out(std::uint16_t entry) const {
  CornerChain chains[8];
  corner_chains(voxels_->entries[entry], 0, chains);
  for (unsigned c = 0; c < 8; ++c) {
    std::atomic_ref<PortShare>(port_shares_[8 * std::size_t{entry} + c])
        .store(port_share(chains[c], c), std::memory_order_relaxed);
    std::atomic_ref<FanShare>(shares_[8 * std::size_t{entry} + c]).store(fan_share(chains[c], c), std::memory_order_relaxed);
  }
  // Released: a thread that sees the byte sees the shares.
  std::atomic_ref<std::uint8_t>(ready_[entry]).store(1, std::memory_order_release);
}

const CoarseFanTable& coarse_fan_table(bool reversed_axes) {
  static const CoarseFanTable table(coarse_voxel_table());
  if (!reversed_axes) return table;
  static const CoarseFanTable mirrored(coarse_voxel_table(true));
  return mirrored;
}

}  // namespace keymesh::generate
