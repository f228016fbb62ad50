#pragma once
// KEY-REDUCE's structured plan for marching cubes (count, scan, write): the
// partition of the edge keys computed from the classification alone, so the
// soup of keys is never written.
//
// On a voxel grid the keys are implicit edge ids, 3 * point_id + axis, and
// the set of keys the soup would hold is known before the soup exists: it is
// the set of cut edges (every cut edge of a voxel is a corner of one of its
// triangles). KEY-REDUCE's dense plan numbers the present keys by their rank
// in key order; here that rank is computed from counts instead of a bitmap of
// the soup:
//   1. count  every grid row (j, k) counts its cut x, y and z edges (keys
//             3p, 3p+1, 3p+2 of its points p) and every voxel row its
//             triangles;
//   2. scan   exclusive prefix sums give each row the id of its first point
//             and of its first triangle (rows in key order: k, then j);
//   3. write  every row writes its points at their final ids, every voxel
//             row its triangles with final point ids: the rank of edge
//             (i, axis) in row r is the row's first id plus the cut edges of
//             the row before it, read off the row's cut bits with popcounts.
// The ids, hence the points, the triangles and every byte of the output, are
// those of the dense and sort plans (key order); a test holds them equal.
// Memory: the inside bits (one bit per sample), two offsets per row and a
// byte per cut voxel (its cube case, kept from the count pass for the write
// pass), then the output arrays at their final size, each written once.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <memory>
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/core/uninitialized_array.hpp"
#include "keymesh/generate/contour/marching_cubes_table.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/scan.hpp"
#include "voxel_bits.hpp"

namespace keymesh::generate {

// The cut edges whose first point lies in grid row (j, k), one bit per i, by
// axis: x (i, i+1), y (j, j+1), z (k, k+1). Planes above `last_plane` add no
// z edge (the slab's top plane, or the plane below a ghost).
struct RowCuts {
  const std::uint64_t* in = nullptr;      // row (j, k)
  const std::uint64_t* next_y = nullptr;  // row (j + 1, k), or null on the last row
  const std::uint64_t* next_z = nullptr;  // row (j, k + 1), or null on the last plane
  Id data_words = 0;                      // words holding samples: ceil(nx / 64)
  Id last_x_word = 0;                     // the word of sample nx - 1, which starts no x edge
  std::uint64_t last_x_mask = 0;          // ~bit of sample nx - 1 in that word

  [[gnu::always_inline]] RowCuts(const InsideBits& bits, const GridShape& s, Id j, Id k, Id last_plane) {
    in = bits.row(j, k, s.ny);
    next_y = j + 1 < s.ny ? bits.row(j + 1, k, s.ny) : nullptr;
    next_z = k < last_plane ? bits.row(j, k + 1, s.ny) : nullptr;
    data_words = (s.nx + 63) / 64;
    last_x_word = (s.nx - 1) / 64;
    last_x_mask = ~(std::uint64_t{1} << ((s.nx - 1) % 64));
  }

  struct Words {
    std::uint64_t x = 0, y = 0, z = 0;
    int count() const { return std::popcount(x) + std::popcount(y) + std::popcount(z); }
  };

  // Word q (zero past the samples).
  [[gnu::always_inline]] Words word(Id q) const {
    Words w;
    if (q >= data_words) return w;
    const std::uint64_t a = in[q];
    w.x = a ^ ((a >> 1) | (in[q + 1] << 63));
    if (q == last_x_word) w.x &= last_x_mask;
    if (next_y) w.y = a ^ next_y[q];
    if (next_z) w.z = a ^ next_z[q];
    return w;
  }

  Id count() const {
    Id c = 0;
    for (Id q = 0; q < data_words; ++q) c += word(q).count();
    return c;
  }

  // Calls f(i, x, y, z) for every i where an edge starts that is cut, in
  // increasing i; x, y, z (0 or 1) say which of its three edges are.
  template <class F>
  void for_each_position(F&& f) const {
    for (Id q = 0; q < data_words; ++q) {
      const Words w = word(q);
      std::uint64_t any = w.x | w.y | w.z;
      while (any) {
        const int b = std::countr_zero(any);
        any &= any - 1;
        f(64 * q + b, static_cast<std::uint32_t>((w.x >> b) & 1), static_cast<std::uint32_t>((w.y >> b) & 1),
          static_cast<std::uint32_t>((w.z >> b) & 1));
      }
    }
  }
};

// The point ids of one grid row's cut edges, by axis and i: ids[axis][i] is
// the id of edge (i, axis) when that edge is cut (other entries are stale).
// Filled from the row's cut bits in one pass over its cut positions, in key
// order (i, then axis), so each id is the row's first id plus a running count.
// The arrays are a view of the caller's scratch (3 nx ids).
struct RowIds {
  std::uint32_t* ids[3];

  RowIds(std::uint32_t* scratch, Id nx) : ids{scratch, scratch + nx, scratch + 2 * nx} {}

  // Also calls cut(id, i, x, y, z) at every position, id the position's
  // first id (the point writer of the row that owns it; a no-op otherwise).
  template <class Cut>
  void fill(const RowCuts& cuts, Id first, Cut&& cut) {
    auto id = static_cast<std::uint32_t>(first);
    // Branch-free: every axis gets the running id, which moves on past the
    // edges that are cut.
    cuts.for_each_position([&](Id i, std::uint32_t x, std::uint32_t y, std::uint32_t z) {
      ids[0][i] = id;
      ids[1][i] = id + x;
      ids[2][i] = id + x + y;
      cut(id, i, x, y, z);
      id += x + y + z;
    });
  }
};

// The voxel rows (j, k), k in [kb, ke), cut into bricks of kRun consecutive
// j by kLayers consecutive k: the unit of work of both the count pass and
// the write pass, so that the write pass finds a brick's cut voxels where
// the count pass left them. Fixed by the grid alone (not by the threads).
struct VoxelBricks {
  static constexpr Id kRun = 16;    // voxel rows (j) per brick
  static constexpr Id kLayers = 8;  // voxel layers (k) per brick
  Id kb = 0, ke = 0, ny = 0, runs = 0, stacks = 0;

  VoxelBricks(const GridShape& s, Id kb_, Id ke_)
      : kb(kb_), ke(ke_), ny(s.ny), runs((s.ny - 1 + kRun - 1) / kRun), stacks((ke_ - kb_ + kLayers - 1) / kLayers) {}
  Id count() const { return runs * stacks; }
  Id k_begin(Id b) const { return kb + (b / runs) * kLayers; }
  Id k_end(Id b) const { return std::min(ke, k_begin(b) + kLayers); }
  Id j_begin(Id b) const { return (b % runs) * kRun; }
  Id j_end(Id b) const { return std::min(ny - 1, j_begin(b) + kRun); }
  Id brick_of(Id j, Id k) const { return ((k - kb) / kLayers) * runs + j / kRun; }
};

// One brick's cut voxels' cube cases, a byte each, in the brick's row
// order (k, then j; i increasing) as the count pass finds them, so that the
// write pass, walking the same voxels, reads their cases instead of
// computing them again. Storage sized by a bound before it is written (no
// check per voxel, no fill: the bound is loose, and only the bytes written
// are touched) and kept for later calls.
struct BrickCases {
  KeptArray<std::uint8_t> cases;

  // The most cut voxels a voxel row of nx samples has when its four grid
  // rows have `cut_edges` cut edges in all: each of its cut voxels has one
  // of them, and an edge is shared by two voxels of the row at most.
  static Id most_per_row(Id nx, Id cut_edges) { return std::min(nx - 1, 2 * cut_edges); }
};

// Point and triangle counts of one isovalue's rows, and their prefix sums.
struct RowCounts {
  std::vector<Id> point_first;     // grid rows (j, k), k in [kb, ke]: first point id; one more at the end
  std::vector<Id> triangle_first;  // voxel rows (j, k), j < ny - 1, k in [kb, ke): first triangle
  std::vector<BrickCases> brick_cases;  // every brick's, as the count pass found them
};

// Step 1 for the grid rows of planes [kb, ke] alone: their cut edges
// counted and scanned into rc.point_first, ids starting at `first_point`.
// count_rows adds the voxel rows; the coarse pass (contour_coarse_rows.hpp)
// walks the voxels itself, once.
inline void count_grid_rows(const InsideBits& bits, const GridShape& s, Id kb, Id ke, Id first_point, RowCounts& rc) {
  const Id grid_rows = s.ny * (ke - kb + 1);
  rc.point_first.assign(static_cast<std::size_t>(grid_rows + 1), 0);
  parallel::for_each_dynamic(grid_rows, [&](Id r) {
    rc.point_first[r] = RowCuts(bits, s, r % s.ny, kb + r / s.ny, ke).count();
  }, 8);
  parallel::exclusive_scan(rc.point_first.data(), rc.point_first.data(), grid_rows + 1);
  if (first_point)  // a later isovalue: ids follow the earlier ones'
    parallel::for_each(grid_rows + 1, [&](Id r) { rc.point_first[r] += first_point; });
}

// Counts rows of planes [kb, ke] (voxel layers [kb, ke)) and scans them, ids
// starting at `first_point` and `first_triangle`.
inline void count_rows(const InsideBits& bits, const GridShape& s, Id kb, Id ke, Id first_point, Id first_triangle,
                       RowCounts& rc) {
  const auto& table = *s.table;
  const Id voxel_rows = (s.ny - 1) * (ke - kb);
  count_grid_rows(bits, s, kb, ke, first_point, rc);
  rc.triangle_first.assign(static_cast<std::size_t>(voxel_rows + 1), 0);
  // Triangles per voxel row, brick by brick; each brick's cut voxels kept
  // (its vector's storage too, for the next isovalue or call).
  const VoxelBricks bricks(s, kb, ke);
  rc.brick_cases.resize(static_cast<std::size_t>(bricks.count()));
  parallel::for_each_dynamic(bricks.count(), [&](Id b) {
    // Room for the brick's cases, from its grid rows' cut edges.
    auto cut_edges = [&](Id j, Id k) {
      const Id r = (k - kb) * s.ny + j;
      return rc.point_first[r + 1] - rc.point_first[r];
    };
    Id room = 0;
    for (Id k = bricks.k_begin(b); k < bricks.k_end(b); ++k)
      for (Id j = bricks.j_begin(b); j < bricks.j_end(b); ++j)
        room += BrickCases::most_per_row(
            s.nx, cut_edges(j, k) + cut_edges(j + 1, k) + cut_edges(j, k + 1) + cut_edges(j + 1, k + 1));
    std::uint8_t* cases = rc.brick_cases[b].cases.room_for(static_cast<std::size_t>(room));
    for (Id k = bricks.k_begin(b); k < bricks.k_end(b); ++k)
      for (Id j = bricks.j_begin(b); j < bricks.j_end(b); ++j) {
        Id t = 0;
        for_each_cut_voxel(bits, s, j, k, [&](Id, unsigned cube_case) {
          t += table.triangle_count[cube_case];
          *cases++ = static_cast<std::uint8_t>(cube_case);
        });
        rc.triangle_first[(k - kb) * (s.ny - 1) + j] = t;
      }
  }, 1);
  parallel::exclusive_scan(rc.triangle_first.data(), rc.triangle_first.data(), voxel_rows + 1);
  if (first_triangle)
    parallel::for_each(voxel_rows + 1, [&](Id r) { rc.triangle_first[r] += first_triangle; });
}

// Writes the triangles of voxel rows (j, k), k in [kb, ke), with final point
// ids, to connectivity (3 per triangle) at their scanned offsets, and calls
// emit(id, i, j, k, axis) once for every cut edge of grid rows of planes
// [kb, ke], id its point id (key order). A voxel's 12 edges lie in grid rows
// (j, k), (j + 1, k), (j, k + 1), (j + 1, k + 1); their ids come from those
// rows' RowIds. A task takes a brick of voxel rows, kRun consecutive j by
// kLayers consecutive k, and keeps the RowIds of two planes of its grid
// rows: plane k + 1's become plane k's for the next layer, so a grid row's
// ids are filled once per brick that reads them (twice only on a brick's
// top plane). The points of a grid row are emitted while its ids are
// filled, by the one brick that owns the row (its planes but the top one,
// unless the top is plane ke; its rows but the last, unless that is row
// ny - 1), so no row is read again for its points. Each task calls its own
// copy of `emit`, which may thus keep what it learns about the task's rows.
template <class Emit>
void write_rows(const InsideBits& bits, const GridShape& s, Id kb, Id ke, const RowCounts& rc,
                PointIndex* connectivity, const Emit& emit_points) {
  const auto& table = *s.table;
  const VoxelBricks bricks(s, kb, ke);
  constexpr Id kRun = VoxelBricks::kRun;
  parallel::for_each_dynamic(bricks.count(), [&](Id task) {
    const Id k_begin = bricks.k_begin(task), k_end = bricks.k_end(task);
    const Id j_begin = bricks.j_begin(task), j_end = bricks.j_end(task);
    Emit emit = emit_points;
    // The cases of the brick's cut voxels, in the order it visits them.
    const std::uint8_t* cases = rc.brick_cases[task].cases.data();
    auto stored_case = [&](int, const CornerWords&) { return unsigned{*cases++}; };
    // Grid rows j_begin .. j_end of two planes, in this thread's scratch.
    thread_local std::vector<std::uint32_t> scratch;
    const Id row_ids = 3 * s.nx;
    if (static_cast<Id>(scratch.size()) < 2 * (kRun + 1) * row_ids)
      scratch.resize(static_cast<std::size_t>(2 * (kRun + 1) * row_ids));
    auto ids_of = [&](int plane, Id j) {
      return RowIds(scratch.data() + (plane * (kRun + 1) + (j - j_begin)) * row_ids, s.nx);
    };
    // Fills grid row (j, k_)'s ids, and writes its points when this brick owns it.
    auto fill = [&](int plane, Id j, Id k_) {
      RowIds row = ids_of(plane, j);
      const RowCuts cuts(bits, s, j, k_, ke);
      const Id first = rc.point_first[(k_ - kb) * s.ny + j];
      const bool owned = (k_ < k_end || k_ == ke) && (j < j_end || j == s.ny - 1);
      if (!owned) return row.fill(cuts, first, [](std::uint32_t, Id, std::uint32_t, std::uint32_t, std::uint32_t) {});
      row.fill(cuts, first, [&](std::uint32_t id, Id i, std::uint32_t x, std::uint32_t y, std::uint32_t z) {
        if (x) emit(Id{id}, i, j, k_, 0);
        if (y) emit(Id{id + x}, i, j, k_, 1);
        if (z) emit(Id{id + x + y}, i, j, k_, 2);
      });
    };
    int lo = 0;  // the plane of layer k's lower grid rows
    for (Id j = j_begin; j <= j_end; ++j) fill(lo, j, k_begin);
    for (Id k = k_begin; k < k_end; ++k) {
      const int hi = lo ^ 1;
      for (Id j = j_begin; j <= j_end; ++j) fill(hi, j, k + 1);
      for (Id j = j_begin; j < j_end; ++j) {
        // Cube edge e's id at voxel i is edge_ids[e][i]: its row's array for
        // its axis, shifted by its x offset.
        const std::uint32_t* edge_ids[12];
        for (int e = 0; e < 12; ++e) {
          const auto& ce = table.edges[e];
          edge_ids[e] = ids_of(ce.dz ? hi : lo, j + ce.dy).ids[ce.axis] + ce.dx;
        }
        PointIndex* out = connectivity + 3 * rc.triangle_first[(k - kb) * (s.ny - 1) + j];
        for_each_cut_voxel(bits, s, j, k, stored_case, [&](Id i, unsigned cube_case) {
          const std::uint8_t* e = table.triangle_edges[cube_case].data();
          for (int t = table.triangle_count[cube_case]; t > 0; --t, e += 3, out += 3) {
            out[0] = edge_ids[e[0]][i];
            out[1] = edge_ids[e[1]][i];
            out[2] = edge_ids[e[2]][i];
          }
        });
      }
      lo = hi;
    }
  }, 1);
}

}  // namespace keymesh::generate
