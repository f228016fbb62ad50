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

CoarseFanTable::CoarseFanTable() {
  const CoarseVoxelTable& voxels = coarse_voxel_table();
  if (voxels.first[0] != 0 || ((voxels.entries[0] >> kCoarseCountShift) & 7u) != 0)
    throw std::logic_error("coarse_fan_table: entry 0 is not the voxel without triangles");
  shares_.reset(static_cast<FanShare*>(std::calloc(8 * voxels.entries.size(), sizeof(FanShare))));
  if (!shares_) throw std::bad_alloc();
}

void CoarseFanTable::work_out(std::uint16_t entry) const {
  CornerChain chains[8];
  corner_chains(coarse_voxel_table().entries[entry], 0, chains);
  // Corner 0 last, released: a thread that sees it sees the others.
  for (unsigned c = 8; c-- > 0;)
    std::atomic_ref<FanShare>(shares_[8 * std::size_t{entry} + c])
        .store(fan_share(chains[c], c), c ? std::memory_order_relaxed : std::memory_order_release);
}

const CoarseFanTable& coarse_fan_table() {
  static const CoarseFanTable table;
  return table;
}

}  // namespace keymesh::generate
