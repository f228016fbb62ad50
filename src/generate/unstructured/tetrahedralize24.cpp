// Scheme 24: face-centred tetrahedralization of hexahedra (see tetrahedralize.hpp).
#include <algorithm>
#include <array>
#include <limits>
#include <string>
#include <vector>

#include "keymesh/mesh/fields.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/core/uninitialized_array.hpp"
#include "keymesh/core/progress.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/mesh/cell_tables.hpp"
#include "keymesh/mesh/keys.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/keyreduce/weld.hpp"

namespace keymesh::generate {

namespace {

// Corners in bit order, faces as corner cycles (mesh/cell_tables.hpp).
constexpr const auto& kFaceCycle = cells::kHexFaceCycle;

// The face centres of the soup: for every (cell, face) pair its group (the
// face-centre index) and for every group the first pair naming it.
struct FaceGroups {
  Array<std::uint32_t> index_map;
  std::vector<std::uint32_t> first;
};

template <class K, class Position>
FaceGroups group_faces(const K* keys, Id n, bool dense, K key_range, int key_bits, bool vertex_weld,
                       Position&& position) {
  keyreduce::WeldSpec<K> spec;
  spec.plan = vertex_weld ? keyreduce::WeldPlan::ByPosition
              : dense     ? keyreduce::WeldPlan::Dense
                          : keyreduce::WeldPlan::Sort;
  spec.key_range = key_range;
  spec.key_bits = key_bits;
  FaceGroups out;
  // The first pair of each group: a face centre is computed from the cell
  // that names it first, whichever plan grouped it.
  auto g = keyreduce::weld(keys, n, spec, position, {nullptr, &out.first});
  out.index_map = std::move(g.index_map);
  return out;
}

// The 24 tets of a cell (tet_kernels.hpp's hex_tets24), handed to out(k, ids).
template <class Out>
void emit_cell(const std::uint64_t corner[8], const std::uint64_t face[6], std::uint64_t centre, const float* P,
               Out&& out) {
  std::uint64_t tets[24][4];
  hex_tets24(corner, face, centre, P, tets);
  for (int k = 0; k < 24; ++k) out(k, tets[k]);
}

// The corner ids of face pair % 6 of cell pair / 6, in cycle order.
template <class CornerOf>
void face_ids(const CornerOf& corner_of, Id pair, std::uint64_t ids[4]) {
  for (int c = 0; c < 4; ++c) ids[c] = corner_of(pair / 6, kFaceCycle[pair % 6][c]);
}

// The reduce and emit half both inputs share, once the faces are welded:
// the input points, then a face centre per group (from the group's first
// pair) and a centre per cell, fields averaged alike; 24 tets per cell.
// corner_of(cell, bit corner) gives a corner's point id.
template <class CornerOf>
UnstructuredGrid assemble24(const Array<float>& points, const std::vector<Field>& fields, Id cells,
                            const CornerOf& corner_of, const FaceGroups& g) {
  const Id N = static_cast<Id>(points.size() / 3), F = static_cast<Id>(g.first.size()), total = N + F + cells;
  if (total > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("tetrahedralize --scheme 24: " + std::to_string(total) + " points exceed 2^32 - 1");
  const float* P = points.data();
  UnstructuredGrid out;
  out.uniform_type = CellType::Tetra;
  extend_points(points, total, out.points);
  out.point_fields = extend_point_fields(fields, total);
  parallel::for_each(F, [&](Id face) {
    std::uint64_t ids[4];
    face_ids(corner_of, g.first[face], ids);
    mean_position(P, ids, 4, &out.points[3 * (N + face)]);
    average_point_fields(fields, out.point_fields, N + face, ids, 4);
  });
  parallel::for_each(cells, [&](Id v) {
    std::uint64_t ids[8];
    for (int c = 0; c < 8; ++c) ids[c] = corner_of(v, c);
    mean_position(P, ids, 8, &out.points[3 * (N + F + v)]);
    average_point_fields(fields, out.point_fields, N + F + v, ids, 8);
  });
  progress::report("tetrahedralize 24: tets", 0.7);
  out.connectivity = IndexArray::for_ids(static_cast<std::uint64_t>(total), static_cast<std::size_t>(96 * cells));
  const float* Q = out.points.data();
  out.connectivity.visit_mut([&](auto conn) {
    using I = typename decltype(conn)::value_type;
    parallel::for_each(cells, [&](Id v) {
      std::uint64_t c8[8], f6[6];
      for (int c = 0; c < 8; ++c) c8[c] = corner_of(v, c);
      for (int f = 0; f < 6; ++f) f6[f] = static_cast<std::uint64_t>(N + g.index_map[6 * v + f]);
      emit_cell(c8, f6, static_cast<std::uint64_t>(N + F + v), Q, [&](int k, const std::uint64_t* t) {
        for (int x = 0; x < 4; ++x) conn[96 * v + 4 * k + x] = static_cast<I>(t[x]);
      });
    });
  });
  return out;
}

}  // namespace

// Voxels: the corners are the grid points (with the samples as a field),
// the cells implicit, face f of voxel v keyed by 3 * (its lower corner) +
// its normal axis (dense plan).
void check_tetrahedralize24_input(const ImageGrid& grid) {
  for (int a = 0; a < 3; ++a)
    if (grid.dims[a] < 2)
      throw InputError("tetrahedralize: grid has " + std::to_string(grid.dims[a]) + " point(s) along axis " + "xyz"[a] +
                       " (need at least 2)");
  const Id N = grid.num_points(), cells = (grid.dims[0] - 1) * (grid.dims[1] - 1) * (grid.dims[2] - 1);
  if (6 * cells > Id{std::numeric_limits<std::uint32_t>::max()} || N + 3 * N + cells > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("tetrahedralize --scheme 24: " + std::to_string(cells) + " voxels exceed the supported size");
}

UnstructuredGrid tetrahedralize24(const ImageGrid& grid, bool vertex_weld) {
  check_tetrahedralize24_input(grid);
  const UnstructuredGrid corners = grid_points(grid);
  const Id nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2], nxy = nx * ny, N = nxy * nz;
  const Id cells = (nx - 1) * (ny - 1) * (nz - 1);
  auto cell_corner = [&](Id v, int c) {
    const Id i = v % (nx - 1), j = (v / (nx - 1)) % (ny - 1), k = v / ((nx - 1) * (ny - 1));
    return static_cast<std::uint64_t>((i + (c & 1)) + nx * (j + ((c >> 1) & 1)) + nxy * (k + ((c >> 2) & 1)));
  };
  progress::report("tetrahedralize 24: face keys", 0.1);
  auto keys = uninitialized_array<std::uint64_t>(static_cast<std::size_t>(6 * cells));
  parallel::for_each(cells, [&](Id v) {
    const std::uint64_t p0 = cell_corner(v, 0);
    const std::uint64_t step[3] = {1, std::uint64_t(nx), std::uint64_t(nxy)};
    for (int f = 0; f < 6; ++f) {
      const int axis = f / 2;
      keys[6 * v + f] = 3 * (p0 + (f & 1) * step[axis]) + std::uint64_t(axis);
    }
  });
  auto face_centre = [&](Id pair, float* xyz) {
    std::uint64_t ids[4];
    face_ids(cell_corner, pair, ids);
    mean_position(corners.points.data(), ids, 4, xyz);
  };
  progress::report("tetrahedralize 24: weld face centres", 0.25);
  const FaceGroups g =
      group_faces<std::uint64_t>(keys.get(), 6 * cells, true, std::uint64_t(3 * N), 0, vertex_weld, face_centre);
  keys.reset();  // before the output is allocated
  progress::report("tetrahedralize 24: points", 0.5);
  return assemble24(corners.points, corners.point_fields, cells, cell_corner, g);
}

// Hexahedra: a quad face is named by its smallest corner and the corner
// diagonally opposite it (sort plan): in a conforming mesh no two faces
// share a diagonal.
UnstructuredGrid tetrahedralize24(const UnstructuredGrid& hexes, bool vertex_weld) {
  hexes.validate("tetrahedralize input");
  const Id cells = hexes.num_cells(), N = hexes.num_points();
  const auto corner = cells::hex_corners(hexes, "tetrahedralize --scheme 24");
  if (6 * cells > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("tetrahedralize --scheme 24: " + std::to_string(cells) + " cells exceed the supported size");
  auto cell_corner = [&](Id v, int c) { return corner[v][c]; };
  const EdgeKeys ek = EdgeKeys::for_points(N, "tetrahedralize --scheme 24");
  auto keys = uninitialized_array<std::uint64_t>(static_cast<std::size_t>(6 * cells));
  parallel::for_each(cells, [&](Id c) {
    for (int f = 0; f < 6; ++f) {
      std::uint64_t cycle[4];
      face_ids(cell_corner, 6 * c + f, cycle);
      keys[6 * c + f] = ek.quad(cycle);
    }
  });
  auto face_centre = [&](Id pair, float* xyz) {
    std::uint64_t ids[4];
    face_ids(cell_corner, pair, ids);
    mean_position(hexes.points.data(), ids, 4, xyz);
  };
  const FaceGroups g =
      group_faces<std::uint64_t>(keys.get(), 6 * cells, false, 0, ek.key_bits(), vertex_weld, face_centre);
  keys.reset();  // before the output is allocated
  UnstructuredGrid out = assemble24(hexes.points, hexes.point_fields, cells, cell_corner, g);
  out.cell_fields = repeat_cell_fields(hexes.cell_fields, cells, 24);
  return out;
}

}  // namespace keymesh::generate
