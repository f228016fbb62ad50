#pragma once
// The tetrahedralizations of a voxel grid (tetrahedralize.hpp) over the device
// layer (keymesh/device/), written once for every device:
//  - 5 tets per voxel: a position and a scalar per grid point, twenty corner
//    ids per voxel (no keys: every point passes through);
//  - 24 tets per voxel: a key per (voxel, face), the face's implicit id
//    3 * (its lower corner) + its normal axis -> KEY-REDUCE's grouping (one
//    face centre per group, in key order, from the group's first pair) -> a
//    centre per voxel -> 24 tets per voxel from the index map.
// Equal to tetrahedralize5(grid) and tetrahedralize24(grid) bit for bit
// (ctest runs them on the CPU device:
// tests/generate/unstructured/tetrahedralize_device_test.cpp).
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>

#include "keymesh/core/device.hpp"
#include "keymesh/device/algorithms.hpp"
#include "keymesh/device/key_groups.hpp"
#include "keymesh/mesh/fields.hpp"
#include "keymesh/generate/unstructured/tet_kernels.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::generate {

// tetrahedralize5(grid) and tetrahedralize24(grid) through the device paths
// on the CPU device.
UnstructuredGrid tetrahedralize5_on_cpu_device(const ImageGrid& grid);
UnstructuredGrid tetrahedralize24_on_cpu_device(const ImageGrid& grid);

namespace device_tetrahedralize {

template <class T>
struct PointsAndScalars {
  GridPoints where;
  const T* samples;
  float* xyz;
  float* scalar;
  KEYMESH_HD void operator()(Id p) const {
    where.position(p, xyz + 3 * p);
    scalar[p] = static_cast<float>(samples[p]);
  }
};

// Voxel v's five tets, the split alternating with the parity of i + j + k
// (shared faces get the same diagonal); a mirrored grid swaps two corners.
template <class I>
struct FiveTets {
  const FiveTetSplits* split;
  Id nx, nxy, vx, vy;
  Id corner_offset[8];
  bool mirrored;
  I* out;
  KEYMESH_HD void operator()(Id v) const {
    const Id i = v % vx, r = v / vx, j = r % vy, k = r / vy;
    const Id base = i + nx * j + nxy * k;
    const int parity = static_cast<int>((i + j + k) & 1);
    I* o = out + 20 * v;
    for (int t = 0; t < 5; ++t) {
      const std::uint8_t* tet = split->tet[parity][t];
      o[4 * t + 0] = static_cast<I>(base + corner_offset[tet[0]]);
      o[4 * t + 1] = static_cast<I>(base + corner_offset[tet[1]]);
      o[4 * t + 2] = static_cast<I>(base + corner_offset[mirrored ? tet[3] : tet[2]]);
      o[4 * t + 3] = static_cast<I>(base + corner_offset[mirrored ? tet[2] : tet[3]]);
    }
  }
};

template <class D, class I>
Array<I> five_tets(const D& d, const ImageGrid& grid) {
  const Id nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2], nxy = nx * ny;
  const Id voxels = (nx - 1) * (ny - 1) * (nz - 1);
  const auto split = d.upload(&five_tet_splits(), 1);
  FiveTets<I> f{split.data(), nx, nxy, nx - 1, ny - 1, {}, false, nullptr};
  for (int c = 0; c < 8; ++c) f.corner_offset[c] = (c & 1) + nx * ((c >> 1) & 1) + nxy * ((c >> 2) & 1);
  f.mirrored = (grid.spacing[0] < 0) != ((grid.spacing[1] < 0) != (grid.spacing[2] < 0));
  auto ids = d.template allocate<I>(20 * voxels);
  f.out = ids.data();
  d.for_each(voxels, f);
  return d.to_host(std::move(ids));
}

// Corner c (bit order) of voxel v.
struct VoxelCorners {
  Id nx, nxy, vx, vy;
  KEYMESH_HD std::uint64_t operator()(Id v, int c) const {
    const Id i = v % vx, j = (v / vx) % vy, k = v / (vx * vy);
    return static_cast<std::uint64_t>((i + (c & 1)) + nx * (j + ((c >> 1) & 1)) + nxy * (k + ((c >> 2) & 1)));
  }
  // The corner ids of face pair % 6 of voxel pair / 6, in cycle order.
  KEYMESH_HD void face(Id pair, std::uint64_t ids[4]) const {
    constexpr int kCycle[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
    for (int c = 0; c < 4; ++c) ids[c] = (*this)(pair / 6, kCycle[pair % 6][c]);
  }
};

struct FaceKeys {
  VoxelCorners corner;
  std::uint64_t* keys;
  KEYMESH_HD void operator()(Id v) const {
    const std::uint64_t p0 = corner(v, 0);
    const std::uint64_t step[3] = {1, std::uint64_t(corner.nx), std::uint64_t(corner.nxy)};
    for (int f = 0; f < 6; ++f) {
      const int axis = f / 2;
      keys[6 * v + f] = 3 * (p0 + std::uint64_t(f & 1) * step[axis]) + std::uint64_t(axis);
    }
  }
};

// Face centre g (after the N grid points) from its group's first pair, then
// voxel centre v (after the faces): positions and the scalar, means in double.
struct Centres {
  VoxelCorners corner;
  const Id* offsets;
  const std::uint32_t* sorted_pairs;
  Id grid_points, faces;
  float* xyz;
  float* scalar;
  KEYMESH_HD void operator()(Id q) const {
    std::uint64_t ids[8];
    int n = 4;
    if (q < faces) {
      corner.face(sorted_pairs[offsets[q]], ids);
    } else {
      for (int c = 0; c < 8; ++c) ids[c] = corner(q - faces, c);
      n = 8;
    }
    const Id p = grid_points + q;
    mean_tuple(xyz, 3, ids, n, xyz + 3 * p);
    mean_tuple(scalar, 1, ids, n, scalar + p);
  }
};

template <class I>
struct Tets24 {
  VoxelCorners corner;
  const std::uint32_t* index_map;
  Id grid_points, faces;
  const float* xyz;
  I* out;
  KEYMESH_HD void operator()(Id v) const {
    std::uint64_t c8[8], f6[6], tets[24][4];
    for (int c = 0; c < 8; ++c) c8[c] = corner(v, c);
    for (int f = 0; f < 6; ++f) f6[f] = static_cast<std::uint64_t>(grid_points + index_map[6 * v + f]);
    hex_tets24(c8, f6, static_cast<std::uint64_t>(grid_points + faces + v), xyz, tets);
    for (int k = 0; k < 24; ++k)
      for (int x = 0; x < 4; ++x) out[96 * v + 4 * k + x] = static_cast<I>(tets[k][x]);
  }
};

// The grid points' positions and scalars into the first N entries of
// arrays sized for `total` points.
template <class D>
void grid_points_into(const D& d, const ImageGrid& grid, float* xyz, float* scalar) {
  const Id points = grid.num_points();
  const GridPoints where{grid.dims[0], grid.dims[0] * grid.dims[1], {grid.origin[0], grid.origin[1], grid.origin[2]},
                         {grid.spacing[0], grid.spacing[1], grid.spacing[2]}};
  visit_scalars(grid, [&](const auto* host) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(host)>>;
    typename D::template Array<T> holder;
    const T* samples = device::readable(d, host, points, holder);
    d.for_each(points, PointsAndScalars<T>{where, samples, xyz, scalar});
    return 0;
  });
}

}  // namespace device_tetrahedralize

// The device path on device `d`: tetrahedralize5(grid)'s checks (the same
// errors: it sizes nothing before they pass), then the points and tets.
template <class D>
UnstructuredGrid tetrahedralize5_on(const D& d, const ImageGrid& grid) {
  check_tetrahedralize5_input(grid);
  const Id points = grid.num_points();
  UnstructuredGrid out;
  out.uniform_type = CellType::Tetra;
  auto xyz = d.template allocate<float>(3 * points);
  auto scalar = d.template allocate<float>(points);
  device_tetrahedralize::grid_points_into(d, grid, xyz.data(), scalar.data());
  out.points = d.to_host(std::move(xyz));
  out.point_fields.push_back(Field{grid.name, 1, d.to_host(std::move(scalar))});
  out.connectivity = IndexArray::for_ids(static_cast<std::uint64_t>(points), 0);
  if (out.connectivity.wide()) out.connectivity.wide_values() = device_tetrahedralize::five_tets<D, std::uint64_t>(d, grid);
  else out.connectivity.narrow() = device_tetrahedralize::five_tets<D, std::uint32_t>(d, grid);
  return out;
}

// The 24-tet device path on device `d`: tetrahedralize24(grid)'s checks (the
// same errors), then the stages above. KEY-REDUCE's sort plan groups the faces
// (the CPU path's dense plan gives the same groups, in key order).
template <class D>
UnstructuredGrid tetrahedralize24_on(const D& d, const ImageGrid& grid) {
  check_tetrahedralize24_input(grid);
  const Id nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2], N = grid.num_points();
  const Id cells = (nx - 1) * (ny - 1) * (nz - 1);
  const device_tetrahedralize::VoxelCorners corner{nx, nx * ny, nx - 1, ny - 1};
  auto keys = d.template allocate<std::uint64_t>(6 * cells);
  d.for_each(cells, device_tetrahedralize::FaceKeys{corner, keys.data()});
  int key_bits = 0;
  while ((std::uint64_t(3 * N - 1) >> key_bits) != 0) ++key_bits;
  device::KeyGroups<D, std::uint64_t> g = device::group_keys(d, keys.data(), 6 * cells, key_bits);
  const Id F = g.groups, total = N + F + cells;
  if (total > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("tetrahedralize --scheme 24: " + std::to_string(total) + " points exceed 2^32 - 1");
  auto xyz = d.template allocate<float>(3 * total);
  auto scalar = d.template allocate<float>(total);
  device_tetrahedralize::grid_points_into(d, grid, xyz.data(), scalar.data());
  d.for_each(F + cells, device_tetrahedralize::Centres{corner, g.offsets.data(), g.sorted_pairs.data(), N, F,
                                                       xyz.data(), scalar.data()});
  UnstructuredGrid out;
  out.uniform_type = CellType::Tetra;
  out.connectivity = IndexArray::for_ids(static_cast<std::uint64_t>(total), 0);
  auto tets = [&](auto type) {
    using I = decltype(type);
    auto ids = d.template allocate<I>(96 * cells);
    d.for_each(cells, device_tetrahedralize::Tets24<I>{corner, g.index_map.data(), N, F, xyz.data(), ids.data()});
    return d.to_host(std::move(ids));
  };
  if (out.connectivity.wide()) out.connectivity.wide_values() = tets(std::uint64_t{});
  else out.connectivity.narrow() = tets(std::uint32_t{});
  out.points = d.to_host(std::move(xyz));
  out.point_fields.push_back(Field{grid.name, 1, d.to_host(std::move(scalar))});
  return out;
}

}  // namespace keymesh::generate
