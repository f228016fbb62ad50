// KEY-REDUCE on your own keys: weld a triangle soup by the history of its corners.
//
//   soup: 12 triangles of a unit cube, 36 corners,    groups: 8 points, one per cube corner,
//   each corner written with its own copy of the      the soup's copies of it merged (mean);
//   position and the key of the cube corner it was    index_map: the group of every soup
//   made from (x + 2y + 4z)                     ->    corner, i.e. the welded triangle list
//
//   keys:        [ 0 4 6  0 6 2  1 3 7 ... ]   36 keys, values 0..7
//   unique_keys: [ 0 1 2 3 4 5 6 7 ]           one group per distinct key, increasing
//   index_map:   [ 0 4 6  0 6 2  1 3 7 ... ]   here equal to the keys (the keys are 0..7)
//
// No coordinate is compared: corners that came from one cube corner carry one key.
// keyreduce::weld wraps the same partition for generators (examples/map_step.cpp).
#include <array>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "keymesh/analyze/topology.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/keyreduce/reduce.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

#include "expect.hpp"

using namespace keymesh;
using Xyz = std::array<float, 3>;

// Cube corner c sits at (c & 1, c >> 1 & 1, c >> 2 & 1).
static Xyz corner_position(unsigned c) { return {float(c & 1), float(c >> 1 & 1), float(c >> 2 & 1)}; }

int main() {
  // The six faces, each wound outward, each split into two triangles: the
  // soup a generator writes when it makes every triangle on its own.
  const unsigned faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  std::vector<std::uint32_t> keys;
  std::vector<Xyz> soup;
  for (const auto& q : faces)
    for (unsigned c : {q[0], q[1], q[2], q[0], q[2], q[3]}) {
      keys.push_back(c);                   // the history: which cube corner made it
      soup.push_back(corner_position(c));  // the soup's own copy of the position
    }
  const Id pairs = static_cast<Id>(keys.size());

  // Partition: group the pairs by key (sort plan on the 3 significant bits),
  // with the pair order so that values can be reduced per group.
  const keyreduce::Groups<std::uint32_t> groups =
      keyreduce::partition_sort(keys.data(), pairs, 3, keyreduce::Order::Build);

  // Reduce: each group's positions merged, in pair order, into their mean.
  std::vector<Xyz> points(static_cast<std::size_t>(groups.num_groups()));
  keyreduce::reduce_values(
      groups, soup.data(), [](Xyz a, Xyz b) { return Xyz{a[0] + b[0], a[1] + b[1], a[2] + b[2]}; },
      [](Xyz sum, Id count) { return Xyz{sum[0] / float(count), sum[1] / float(count), sum[2] / float(count)}; },
      points.data());

  SurfaceMesh cube;
  for (const Xyz& p : points) cube.points.insert(cube.points.end(), p.begin(), p.end());
  cube.connectivity = groups.index_map;  // the index map is the welded triangle list
  std::printf("%lld corners -> %lld points, %lld triangles\n", static_cast<long long>(pairs),
              static_cast<long long>(cube.num_points()), static_cast<long long>(cube.num_cells()));

  EXPECT(groups.num_groups() == 8);
  for (Id g = 0; g < 8; ++g) {
    EXPECT(groups.unique_keys[g] == g);
    EXPECT(points[g] == corner_position(unsigned(g)));  // each copy was exact, so is their mean
    EXPECT(groups.count(g) >= 3 && groups.count(g) <= 6);
  }
  EXPECT(groups.offsets.back() == pairs);  // every pair in exactly one group
  const analyze::TopologyReport topology = analyze::check_topology(cube);
  EXPECT(topology.closed_manifold);
  EXPECT(topology.euler_characteristic == 2);  // 8 - 18 + 12
  return 0;
}
