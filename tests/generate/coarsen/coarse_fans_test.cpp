// The coarse fan check (src/generate/coarsen/coarse_fans.hpp: fan_verdict, its
// quick test on the shares at the ports and its walk) against a brute force
// over one point's triangles: random 3x3x3 blocks of samples around a point
// (inside bits and, for every cut edge, whether its crossing is nearer the
// far end), each of the eight voxels' coarse triangles read from the voxel
// table, the point's link edges collected and checked for one directed
// cycle through distinct neighbours, three or more (split_nonmanifold's
// one_closed_fan). The verdict must be the walk's alone (the quick test
// clears only what the walk clears), no triangle exactly when the point has
// none, one closed fan only when it is one, and a suspect that is one
// closed fan only when a voxel's share is tangled; corners_at (the bound on
// the split's copies) counts the point's corners.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "generate/coarsen/coarse_fans.hpp"
#include "keymesh/generate/contour/marching_cubes_table.hpp"

using namespace keymesh;
using namespace keymesh::generate;

namespace {

// A 3x3x3 block of grid points, point (x, y, z) at x + 3 y + 9 z; the centre
// (13) is the point checked.
struct Block {
  std::array<bool, 27> inside{};
  std::array<bool, 81> far{};  // by grid edge: 3 * point + axis (edges leaving the block unused)
};

unsigned point_of(unsigned x, unsigned y, unsigned z) { return x + 3 * y + 9 * z; }

// The table entries of the block's eight voxels, voxel o = dx | dy << 1 | dz << 2.
std::array<std::uint16_t, 8> entries_of(const Block& b) {
  const auto& cubes = marching_cubes_table();
  const auto& table = coarse_voxel_table();
  std::array<std::uint16_t, 8> entries{};
  for (unsigned o = 0; o < 8; ++o) {
    const unsigned dx = o & 1u, dy = (o >> 1) & 1u, dz = o >> 2;
    unsigned cube_case = 0, far = 0;
    for (unsigned c = 0; c < 8; ++c)
      if (b.inside[point_of(dx + (c & 1u), dy + ((c >> 1) & 1u), dz + (c >> 2))]) cube_case |= 1u << c;
    for (unsigned e = 0; e < 12; ++e) {
      const auto& edge = cubes.edges[e];
      const unsigned start = point_of(dx + edge.dx, dy + edge.dy, dz + edge.dz);
      if (b.far[3 * start + edge.axis]) far |= 1u << e;
    }
    unsigned far_key = 0;  // the far bits in the far key's order (coarse_cases.hpp)
    for (unsigned bit = 0; bit < 16; ++bit)
      if (kFarKeyEdge[bit] >= 0 && ((far >> kFarKeyEdge[bit]) & 1u)) far_key |= 1u << bit;
    entries[o] = table.index(cube_case, far_key);
  }
  return entries;
}

// The brute force: the point's link edges a -> b, one per coarse triangle
// (13, a, b) of its voxels, counter-clockwise from it.
// `corners` gets their count (the point's corners).
enum class Reference { kNoTriangle, kOneClosedFan, kNotOne };
Reference reference_fan(const std::array<std::uint16_t, 8>& entries, std::size_t& corners) {
  const auto& table = coarse_voxel_table();
  std::vector<std::pair<unsigned, unsigned>> link;
  for (unsigned o = 0; o < 8; ++o) {
    const CoarseVoxel v = table.entries[entries[o]];
    const unsigned count = static_cast<unsigned>((v >> kCoarseCountShift) & 7u);
    for (unsigned t = 0; t < count; ++t) {
      const unsigned x = static_cast<unsigned>(v >> (9 * t)) & 511u;
      unsigned p[3];
      for (unsigned k = 0; k < 3; ++k) {
        const unsigned c = (x >> (3 * k)) & 7u;
        p[k] = point_of((o & 1u) + (c & 1u), ((o >> 1) & 1u) + ((c >> 1) & 1u), (o >> 2) + (c >> 2));
      }
      for (unsigned k = 0; k < 3; ++k)
        if (p[k] == 13) link.emplace_back(p[(k + 1) % 3], p[(k + 2) % 3]);
    }
  }
  corners = link.size();
  if (link.empty()) return Reference::kNoTriangle;
  std::map<unsigned, unsigned> next;
  std::map<unsigned, int> arrivals;
  for (const auto& [a, b] : link) {
    if (a == 13 || b == 13 || next.count(a)) return Reference::kNotOne;
    next[a] = b;
    ++arrivals[b];
  }
  for (const auto& [b, n] : arrivals)
    if (n != 1 || !next.count(b)) return Reference::kNotOne;
  if (link.size() < 3) return Reference::kNotOne;
  unsigned at = link.front().first;
  std::size_t steps = 0;
  do at = next[at], ++steps;
  while (at != link.front().first && steps <= link.size());
  return steps == link.size() ? Reference::kOneClosedFan : Reference::kNotOne;
}

TEST(CoarseFans, VerdictIsTheWalksAndMatchesTheTrianglesAroundThePoint) {
  const CoarseFanTable& table = coarse_fan_table();
  std::mt19937 rng(17);
  std::map<FanVerdict, int> seen;
  int quick = 0, tangled_suspects = 0;
  for (int trial = 0; trial < 300000; ++trial) {
    Block b;
    // Half the blocks from a plane or a sphere through the block (smooth
    // surfaces, where most points are one closed fan), half random bits
    // (tangles, two sheets, folds).
    std::uniform_real_distribution<double> u(-1, 1);
    const bool smooth = trial % 2 == 0;
    const double nx = u(rng), ny = u(rng), nz = u(rng), d = 0.5 * u(rng), r = 1 + u(rng);
    const double p = 0.2 + 0.6 * (u(rng) + 1) / 2;
    for (unsigned z = 0; z < 3; ++z)
      for (unsigned y = 0; y < 3; ++y)
        for (unsigned x = 0; x < 3; ++x) {
          const double px = x - 1.0, py = y - 1.0, pz = z - 1.0;
          const double value = trial % 4 == 0 ? nx * px + ny * py + nz * pz + d
                                              : r - std::sqrt((px - d) * (px - d) + py * py + pz * pz);
          b.inside[point_of(x, y, z)] = smooth ? value >= 0 : std::bernoulli_distribution(p)(rng);
        }
    for (bool& f : b.far) f = rng() & 1u;
    const std::array<std::uint16_t, 8> entries = entries_of(b);
    for (std::uint16_t e : entries) table.prepare(e);
    auto port = [&](unsigned o) { return table.share_at_ports(entries[o], 7u - o); };
    auto share = [&](unsigned o) { return table.share(entries[o], 7u - o); };
    const FanVerdict verdict = fan_verdict(port, share);
    // The walk alone, as before the quick test.
    FanShares walk;
    for (unsigned o = 0; o < 8; ++o) walk.add(share(o));
    const FanVerdict walk_verdict = walk.empty()             ? FanVerdict::kNoTriangle
                                    : walk.one_closed_fan() ? FanVerdict::kOneClosedFan
                                                            : FanVerdict::kSuspect;
    ASSERT_EQ(verdict, walk_verdict) << "trial " << trial;
    std::size_t corners = 0;
    const Reference ref = reference_fan(entries, corners);
    // The bound on a suspect's copies counts its corners as the triangles do.
    std::size_t counted = 0;
    for (unsigned o = 0; o < 8; ++o) counted += corners_at(coarse_voxel_table().entries[entries[o]], 7u - o);
    ASSERT_EQ(counted, corners) << "trial " << trial;
    ASSERT_EQ(verdict == FanVerdict::kNoTriangle, ref == Reference::kNoTriangle) << "trial " << trial;
    if (verdict == FanVerdict::kOneClosedFan) {
      ASSERT_EQ(ref, Reference::kOneClosedFan) << "trial " << trial;
    }
    if (ref == Reference::kNotOne) {
      ASSERT_EQ(verdict, FanVerdict::kSuspect) << "trial " << trial;
    }
    bool tangled = false;
    for (unsigned o = 0; o < 8; ++o) {
      CornerChain chains[8];
      corner_chains(coarse_voxel_table().entries[entries[o]], 0, chains);
      tangled = tangled || (chains[7 - o] >> kChainKindShift) == kTangled;
    }
    if (verdict == FanVerdict::kSuspect && ref == Reference::kOneClosedFan) {
      ASSERT_TRUE(tangled) << "trial " << trial;
      ++tangled_suspects;
    }
    ++seen[verdict];
    // Cleared by the quick test: three to five paths between ports.
    PortShare sum = 0;
    for (unsigned o = 0; o < 8; ++o) sum += port(o);
    quick += verdict == FanVerdict::kOneClosedFan && (sum & kPortWeight) <= 5;
  }
  // Every outcome is met, and the quick test decides most closed fans.
  EXPECT_GT(seen[FanVerdict::kNoTriangle], 1000);
  EXPECT_GT(seen[FanVerdict::kSuspect], 1000);
  EXPECT_GT(seen[FanVerdict::kOneClosedFan], 10000);
  EXPECT_GT(quick, seen[FanVerdict::kOneClosedFan] / 2);
  EXPECT_GT(tangled_suspects, 0);
}

}  // namespace
