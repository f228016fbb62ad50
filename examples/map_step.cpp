// A new generator is its map step: voxel faces ("cuberille"), welded by KEY-REDUCE.
//
//   a block of voxels with a square hole       a quad per face between an inside and an
//   (samples != 0 are inside)            ->    outside voxel, its corners welded by key:
//     . . . . . .                              a closed surface, one point per lattice corner
//     . # # # # .                              it touches (a torus: Euler characteristic 0)
//     . # . . # .
//     . # . . # .       map:    every boundary face emits the keys of its 4 corners, the ids
//     . # # # # .               of lattice points: i + (nx+1) * (j + (ny+1) * k)
//     . . . . . .       weld:   keyreduce::weld groups equal keys (dense plan: the keys are
//                               grid ids below a known range); the index map is the quad list
//                       reduce: each point's position from its key, once per group
//
// The generator writes only the keys of the elements its outputs come from; nothing compares
// coordinates (docs/ARCHITECTURE.md, "A new generator is its map step").
#include <bit>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "keymesh/analyze/topology.hpp"
#include "keymesh/keyreduce/weld.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/scan.hpp"

#include "expect.hpp"

using namespace keymesh;

// A voxel's faces (-x, +x, -y, +y, -z, +z), each as 4 of its corners
// (corner c = dx + 2 dy + 4 dz), wound so that the quad faces out of the voxel.
constexpr unsigned kFaceCorners[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                         {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

// The voxel faces between inside (sample != 0) and outside voxels (or the
// grid's border) of a uint8 grid, as quads.
SurfaceMesh voxel_faces(const ImageGrid& grid) {
  const Id nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2], voxels = grid.num_points();
  const auto* sample = static_cast<const std::uint8_t*>(grid.data());
  auto inside = [&](Id i, Id j, Id k) {
    return i >= 0 && j >= 0 && k >= 0 && i < nx && j < ny && k < nz && sample[i + nx * (j + ny * k)] != 0;
  };
  // Bit f of boundary(v): face f of voxel v is on the surface.
  auto boundary = [&](Id v) {
    const Id i = v % nx, j = v / nx % ny, k = v / (nx * ny);
    if (!inside(i, j, k)) return 0u;
    const Id step[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
    unsigned bits = 0;
    for (unsigned f = 0; f < 6; ++f)
      if (!inside(i + step[f][0], j + step[f][1], k + step[f][2])) bits |= 1u << f;
    return bits;
  };
  // Map: count each voxel's pairs (4 per face), scan, then write every face's corner keys.
  std::vector<Id> first(static_cast<std::size_t>(voxels));
  parallel::for_each(voxels, [&](Id v) { first[v] = 4 * std::popcount(boundary(v)); });
  const Id pairs = parallel::exclusive_scan(first);
  const Id cx = nx + 1, cy = ny + 1;  // lattice corners per row and column
  std::vector<std::uint32_t> keys(static_cast<std::size_t>(pairs));
  parallel::for_each(voxels, [&](Id v) {
    const Id i = v % nx, j = v / nx % ny, k = v / (nx * ny);
    Id at = first[v];
    for (unsigned f = 0, bits = boundary(v); f < 6; ++f)
      if (bits >> f & 1)
        for (unsigned c : kFaceCorners[f])
          keys[at++] = static_cast<std::uint32_t>((i + (c & 1)) + cx * ((j + (c >> 1 & 1)) + cy * (k + (c >> 2 & 1))));
  });
  // Weld: one group per lattice corner that some face uses, in key order.
  keyreduce::WeldSpec<std::uint32_t> spec;
  spec.plan = keyreduce::WeldPlan::Dense;
  spec.key_range = static_cast<std::uint32_t>(cx * cy * (nz + 1));
  const auto groups = keyreduce::weld(keys.data(), pairs, spec, [](Id, float*) {});
  // Reduce: a point per group, at its lattice corner (voxels centred on their samples).
  SurfaceMesh out;
  out.points.resize(static_cast<std::size_t>(3 * groups.num_groups()));
  parallel::for_each(groups.num_groups(), [&](Id g) {
    const Id key = groups.unique_keys[g], corner[3] = {key % cx, key / cx % cy, key / (cx * cy)};
    for (int a = 0; a < 3; ++a)
      out.points[3 * g + a] = static_cast<float>(grid.origin[a] + grid.spacing[a] * (double(corner[a]) - 0.5));
  });
  out.connectivity = groups.index_map;  // 4 point ids per quad, in the faces' order
  out.offsets.resize(static_cast<std::size_t>(pairs / 4 + 1));
  parallel::for_each(pairs / 4 + 1, [&](Id q) { out.offsets[q] = static_cast<std::uint64_t>(4 * q); });
  return out;
}

int main() {
  // An 8 x 8 x 6 grid: a 4 x 4 x 2 block of inside voxels with a 2 x 2 hole through it.
  ImageGrid grid;
  grid.allocate({8, 8, 6}, ScalarType::UInt8);
  auto* sample = static_cast<std::uint8_t*>(grid.data());
  for (Id k = 2; k < 4; ++k)
    for (Id j = 2; j < 6; ++j)
      for (Id i = 2; i < 6; ++i) sample[i + 8 * (j + 8 * k)] = !(i >= 3 && i < 5 && j >= 3 && j < 5);

  const SurfaceMesh torus = voxel_faces(grid);
  std::printf("%lld quads, %lld points\n", static_cast<long long>(torus.num_cells()),
              static_cast<long long>(torus.num_points()));
  // Faces by hand: 2 x (16 - 4) top and bottom, 4 x 8 outer walls, 4 x 4 in the hole.
  EXPECT(torus.num_cells() == 72);
  const analyze::TopologyReport topology = analyze::check_topology(torus);
  EXPECT(topology.closed_manifold);
  EXPECT(topology.components == 1);
  EXPECT(topology.euler_characteristic == 0);  // V - E + F = 72 - 144 + 72: one hole
  EXPECT(topology.duplicate_points == 0);      // welded: no two points at one position
  return 0;
}
