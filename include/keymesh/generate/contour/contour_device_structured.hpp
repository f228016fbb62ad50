#pragma once
// Marching cubes on a voxel grid over the device layer, the structured plan
// (count -> scan -> write, as Flying Edges and Warp do; the CPU's own plan in
// contour_rows.hpp, docs/decisions/structured-plan.md): no soup, no sort.
//   count: one thread per grid row (j, k) counts the row's cut edges (x, y
//          and z edges from its points, in key order) and the triangles of
//          voxel row (j, k);
//   scan:  64-bit exclusive scans of the rows' counts give every row its
//          first point id and first triangle: point ids are the ranks of the
//          edge keys 3 point + axis (+ isovalue x 3N), the numbering of
//          contour()'s plans, so the bytes equal theirs;
//   write: one thread per grid row writes its points (id = the row's first
//          + the cut edges before it in the row), one per voxel row its
//          triangles, each corner's id from four running counts, one per
//          grid row its edges lie in.
// Scratch is O(rows): two 64-bit counts per grid row and isovalue.
// The per-point arithmetic is the sort plan's (contour_device.hpp:
// PointOutputs over contour_kernels.hpp's EdgeInterpolator); averaged normals
// sum each point's face normals in contour()'s block order with the sort
// plan's functors, the point's corners grouped by a stable sort of the
// triangle list (the only sort, and only for --normals average).
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "keymesh/core/device.hpp"
#include "keymesh/device/algorithms.hpp"
#include "keymesh/device/key_groups.hpp"
#include "keymesh/generate/contour/contour_device.hpp"

namespace keymesh::generate::device_structured {

using device_contour::PointOutputs;

// `value >= iso` at a grid point, as the sort plan's Classify tests it (NaN
// is outside). An isovalue no sample can be inside of, or every sample is
// (InsideTest's none / all: integer samples), cuts no edge: count_rows skips
// it, so the test here is the comparison alone.
template <class T>
struct Inside {
  const T* samples;
  T threshold;
  KEYMESH_HOT_INLINE KEYMESH_HD bool operator()(Id q) const { return samples[q] >= threshold; }
};

KEYMESH_HOT_INLINE KEYMESH_HD unsigned count3(unsigned m) { return (m & 1u) + ((m >> 1) & 1u) + ((m >> 2) & 1u); }

// A row walk reads each sample of a column once: the inside bits of column
// i of the grid rows (j + a, k + b) around row (j, k), bit w for the w-th
// (a, b) of (0, 0) (1, 0) (0, 1) (1, 1) (2, 0) (2, 1) (0, 2) (1, 2). Bits 0-3 (a, b in {0, 1}) are the four grid rows a voxel
// row's corners lie in (bit dy + 2 dz, so a cube case is two columns' low
// nibbles); the others are the rows their y and z edges end in.
// (Packed in integers: a constant array would need a copy in device memory.)
KEYMESH_HD inline Id window_a(int w) { return (0x4a44u >> 2 * w) & 3u; }
KEYMESH_HD inline Id window_b(int w) { return (0xa450u >> 2 * w) & 3u; }
KEYMESH_HD inline unsigned window_y(int s) { return (0x5341u >> 4 * s) & 15u; }  // the bit of row (a + 1, b), rows 0-3
KEYMESH_HD inline unsigned window_z(int s) { return (0x7632u >> 4 * s) & 15u; }  // the bit of row (a, b + 1)

// The grid and the inside test, as the row functors read them.
template <class T>
struct Rows {
  Inside<T> inside;
  Id nx, ny, nz, nxy;
  const MarchingCubesTable* table;

  // Where the window rows of row (j, k) in `wanted` start (those in the grid; bit w of `in_grid`).
  struct Window {
    Id start[8];
    unsigned in_grid;
  };
  KEYMESH_HD Window window(Id j, Id k, unsigned wanted) const {
    Window win{{}, 0};
    for (int w = 0; w < 8; ++w) {
      const Id jw = j + window_a(w), kw = k + window_b(w);
      win.start[w] = nx * jw + nxy * kw;
      if ((wanted >> w & 1u) && jw < ny && kw < nz) win.in_grid |= 1u << w;
    }
    return win;
  }
  // Column i's inside bits (0 for the window rows outside the grid).
  KEYMESH_HOT_INLINE KEYMESH_HD unsigned column(const Window& win, Id i) const {
    unsigned bits = 0;
    for (int w = 0; w < 8; ++w)
      if (win.in_grid >> w & 1u) bits |= static_cast<unsigned>(inside(i + win.start[w])) << w;
    return bits;
  }
  // Bit a: the edge from grid point i of window row s (0-3) along axis a is
  // cut; c0, c1 are columns i and i + 1.
  KEYMESH_HOT_INLINE KEYMESH_HD unsigned cut_edges(int s, Id i, Id j, Id k, unsigned c0, unsigned c1) const {
    const unsigned in = c0 >> s & 1u;
    unsigned m = 0;
    if (i + 1 < nx && (c1 >> s & 1u) != in) m |= 1u;
    if (j + window_a(s) + 1 < ny && (c0 >> window_y(s) & 1u) != in) m |= 2u;
    if (k + window_b(s) + 1 < nz && (c0 >> window_z(s) & 1u) != in) m |= 4u;
    return m;
  }
  // The cube case of the voxel between columns c0 and c1 (bit `corner` set
  // when that corner is inside), as the sort plan's Classify numbers corners.
  // Corner dx + 2 (dy + 2 dz) is bit dy + 2 dz of column c_dx: the low
  // nibbles of c0 and c1 interleaved.
  KEYMESH_HOT_INLINE KEYMESH_HD static unsigned cube_case(unsigned c0, unsigned c1) {
    return spread(c0 & 15u) | spread(c1 & 15u) << 1;
  }
  KEYMESH_HOT_INLINE KEYMESH_HD static unsigned spread(unsigned x) {
    x = (x | x << 2) & 0x33u;
    return (x | x << 1) & 0x55u;
  }
  KEYMESH_HD bool has_voxels(Id j, Id k) const { return j + 1 < ny && k + 1 < nz; }
};

// Count: grid row r = j + ny k's cut edges and voxel row r's triangles
// (none past the last voxel row).
template <class T>
struct CountRows {
  Rows<T> g;
  std::uint64_t* points;
  std::uint64_t* triangles;
  KEYMESH_HD void operator()(Id r) const {
    const Id j = r % g.ny, k = r / g.ny;
    const bool voxels = g.has_voxels(j, k);
    std::uint64_t p = 0, t = 0;
    const auto win = g.window(j, k, 0xfu);
    unsigned c0 = g.column(win, 0);
    for (Id i = 0; i < g.nx; ++i) {
      const unsigned c1 = i + 1 < g.nx ? g.column(win, i + 1) : 0u;
      p += count3(g.cut_edges(0, i, j, k, c0, c1));
      if (voxels && i + 1 < g.nx) t += g.table->triangle_count[Rows<T>::cube_case(c0, c1)];
      c0 = c1;
    }
    points[r] = p;
    triangles[r] = t;
  }
};

// Write: grid row r's points at their ids, in key order (i, then axis).
template <class T>
struct WriteRowPoints {
  Rows<T> g;
  EdgeInterpolator<T> interp;
  PointOutputs<T> out;
  const std::uint64_t* first;  // the isovalue's scan of CountRows' points (rows + 1: the total last)
  Id base;                     // the isovalue's first point id
  Id iso;
  KEYMESH_HD void operator()(Id r) const {
    const Id j = r % g.ny, k = r / g.ny;
    Id id = base + static_cast<Id>(first[r]);
    if (first[r + 1] == first[r]) return;  // no cut edge
    const auto win = g.window(j, k, 0x7u);
    unsigned c0 = g.column(win, 0);
    for (Id i = 0; i < g.nx; ++i) {
      const unsigned c1 = i + 1 < g.nx ? g.column(win, i + 1) : 0u;
      const unsigned m = g.cut_edges(0, i, j, k, c0, c1);
      for (int axis = 0; axis < 3; ++axis)
        if (m >> axis & 1u) out.write(interp, interp.at(i + g.nx * j + g.nxy * k, i, j, k, axis, iso), id++);
      c0 = c1;
    }
  }
};

// Write: voxel row r's triangles, in voxel and table order (contour()'s).
// A corner's edge starts at grid point (i + dx, j + dy, k + dz): its id is
// that grid row's first, plus the row's cut edges before point i + dx, plus
// the point's cut edges along a smaller axis. The four grid rows' counts run
// along with i, over a window of three columns.
template <class T>
struct WriteRowTriangles {
  Rows<T> g;
  const std::uint64_t* point_first;     // rows + 1 (CountRows' scans, the totals last)
  const std::uint64_t* triangle_first;
  Id point_base, triangle_base;
  PointIndex* connectivity;
  KEYMESH_HD void operator()(Id r) const {
    const Id j = r % g.ny, k = r / g.ny;
    if (!g.has_voxels(j, k) || triangle_first[r + 1] == triangle_first[r]) return;
    Id first[4], before[4] = {0, 0, 0, 0};
    const auto win = g.window(j, k, 0xffu);
    unsigned c0 = g.column(win, 0), c1 = g.column(win, 1);
    unsigned c2 = g.nx > 2 ? g.column(win, 2) : 0u;
    unsigned here[4], next[4];  // cut edges at points i and i + 1 of each row
    for (int s = 0; s < 4; ++s) {
      first[s] = point_base + static_cast<Id>(point_first[j + window_a(s) + g.ny * (k + window_b(s))]);
      here[s] = g.cut_edges(s, 0, j, k, c0, c1);
      next[s] = g.cut_edges(s, 1, j, k, c1, c2);
    }
    PointIndex* o = connectivity + 3 * (triangle_base + static_cast<Id>(triangle_first[r]));
    for (Id i = 0; i + 1 < g.nx; ++i) {
      const unsigned c = Rows<T>::cube_case(c0, c1);
      const int corners = 3 * g.table->triangle_count[c];
      for (int n = 0; n < corners; ++n) {
        const CubeEdge& ce = g.table->edges[g.table->triangle_edges[c][n]];
        const int s = ce.dy + 2 * ce.dz;
        const unsigned lower = (1u << ce.axis) - 1u;
        const Id rank = ce.dx ? before[s] + count3(here[s]) + count3(next[s] & lower) : before[s] + count3(here[s] & lower);
        *o++ = static_cast<PointIndex>(first[s] + rank);
      }
      c0 = c1, c1 = c2;  // columns i + 1, i + 2, i + 3
      c2 = i + 3 < g.nx ? g.column(win, i + 3) : 0u;
      for (int s = 0; s < 4; ++s) {
        before[s] += count3(here[s]);
        here[s] = next[s];
        next[s] = i + 2 < g.nx ? g.cut_edges(s, i + 2, j, k, c1, c2) : 0u;
      }
    }
  }
};

// One isovalue's row counts, scanned: each grid row's first point and
// triangle within the isovalue, and the isovalue's totals.
template <class D>
struct IsoRows {
  typename D::template Array<std::uint64_t> point_first, triangle_first;
  Id points = 0, triangles = 0;
  Id point_base = 0, triangle_base = 0;  // the isovalues before it
};

template <class T, class D>
Rows<T> rows_of(const device_contour::Input<D, T>& in, double iso) {
  const GridShape& s = in.shape;
  return Rows<T>{Inside<T>{in.samples, InsideTest<T>(iso).threshold}, s.nx, s.ny, s.nz, s.nxy, in.table.data()};
}

// Count and scan every isovalue's rows.
template <class D, class T>
std::vector<IsoRows<D>> count_rows(const D& d, const device_contour::Input<D, T>& in, const ContourOptions& opt,
                                   ContourStats& st) {
  const Id rows = in.shape.ny * in.shape.nz;
  std::vector<IsoRows<D>> iso_rows(opt.isovalues.size());
  Id points = 0, triangles = 0;
  for (std::size_t iso = 0; iso < iso_rows.size(); ++iso) {
    IsoRows<D>& ir = iso_rows[iso];
    ir.point_first = d.template allocate<std::uint64_t>(rows + 1);  // + the total
    ir.triangle_first = d.template allocate<std::uint64_t>(rows + 1);
    auto mark = d.begin_stage(&st.classify);
    const InsideTest<T> test(opt.isovalues[iso]);
    const Id counted = test.none || test.all ? 0 : rows;  // no edge cut: every count 0
    d.for_each(counted, CountRows<T>{rows_of(in, opt.isovalues[iso]), ir.point_first.data(), ir.triangle_first.data()});
    device::fill(d, ir.point_first.data() + counted, rows + 1 - counted, std::uint64_t{0});
    device::fill(d, ir.triangle_first.data() + counted, rows + 1 - counted, std::uint64_t{0});
    d.end_stage(mark);
    mark = d.begin_stage(&st.weld);
    ir.points = static_cast<Id>(d.exclusive_scan(ir.point_first.data(), ir.point_first.data(), rows + 1));
    ir.triangles = static_cast<Id>(d.exclusive_scan(ir.triangle_first.data(), ir.triangle_first.data(), rows + 1));
    d.end_stage(mark);
    ir.point_base = points, ir.triangle_base = triangles;
    points += ir.points, triangles += ir.triangles;
  }
  return iso_rows;
}

// Averaged normals: the points' corners grouped (a stable sort of the
// triangle list by point id), summed in contour()'s block order by the sort
// plan's averaged_normals.
template <class D, class T>
typename D::template Array<float> averaged_normals(const D& d, const device_contour::Input<D, T>& in,
                                                   const std::vector<IsoRows<D>>& iso_rows,
                                                   const device_contour::ContourArrays<D>& out) {
  const Id corners = 3 * out.triangles;
  const Id layer_blocks = (in.shape.nz - 1 + kSlabsPerBlock - 1) / kSlabsPerBlock;
  const Id n_iso = static_cast<Id>(iso_rows.size());
  device_contour::Soup<D, std::uint32_t> soup{d.template allocate<std::uint32_t>(corners),
                                              d.template allocate<Id>(n_iso * layer_blocks + 1), corners};
  for (Id iso = 0; iso < n_iso; ++iso)
    d.for_each(layer_blocks, device_contour::BlockStarts{iso_rows[iso].triangle_first.data(),
                                                         kSlabsPerBlock * in.shape.ny,
                                                         3 * iso_rows[iso].triangle_base,
                                                         soup.blocks.data() + iso * layer_blocks});
  device::fill(d, soup.blocks.data() + n_iso * layer_blocks, 1, corners);
  device::copy(d, out.connectivity.data(), corners, soup.keys.data());
  int bits = 0;
  while (bits < 32 && (static_cast<std::uint64_t>(out.points - 1) >> bits) != 0) ++bits;
  const auto g = device::group_keys(d, soup.keys.data(), corners, bits);
  return device_contour::averaged_normals(d, g, soup, out.xyz.data(), out.connectivity.data());
}

// The mesh of every isovalue: the rows counted and scanned, the output
// checked (contour()'s limits) before it is sized, then written once.
template <class D, class T>
device_contour::ContourArrays<D> contour_arrays(const D& d, const device_contour::Input<D, T>& in,
                                                const ContourOptions& opt, ContourStats& st) {
  const std::uint64_t key_range = 3ull * static_cast<std::uint64_t>(in.shape.n) * opt.isovalues.size();
  st.key_bits = key_range <= std::numeric_limits<std::uint32_t>::max() ? 32 : 64;
  const std::vector<IsoRows<D>> iso_rows = count_rows(d, in, opt, st);
  device_contour::ContourArrays<D> out;
  out.points = iso_rows.back().point_base + iso_rows.back().points;
  out.triangles = iso_rows.back().triangle_base + iso_rows.back().triangles;
  st.soup_points = 3 * out.triangles;
  check_contour_output(opt, out.points, out.triangles);
  auto mark = d.begin_stage(&st.generate);
  out.connectivity = d.template allocate_output<std::uint32_t>(3 * out.triangles);
  const Id rows = in.shape.ny * in.shape.nz;
  for (std::size_t iso = 0; iso < iso_rows.size(); ++iso) {
    const IsoRows<D>& ir = iso_rows[iso];
    d.for_each(rows, WriteRowTriangles<T>{rows_of(in, opt.isovalues[iso]), ir.point_first.data(),
                                          ir.triangle_first.data(), ir.point_base, ir.triangle_base,
                                          out.connectivity.data()});
  }
  d.end_stage(mark);
  mark = d.begin_stage(&st.fields);
  const PointOutputs<T> fields = device_contour::point_outputs<T>(d, out, opt, true);
  const EdgeInterpolator<T> interp{in.samples, in.shape, in.isovalues.data(), 3 * in.shape.n};
  for (std::size_t iso = 0; iso < iso_rows.size(); ++iso) {
    const IsoRows<D>& ir = iso_rows[iso];
    d.for_each(rows, WriteRowPoints<T>{rows_of(in, opt.isovalues[iso]), interp, fields, ir.point_first.data(),
                                       ir.point_base, static_cast<Id>(iso)});
  }
  if (opt.normals == ContourNormals::Average && out.triangles > 0)
    out.fields.averaged_normal = averaged_normals(d, in, iso_rows, out);
  else if (opt.normals == ContourNormals::Average)
    out.fields.averaged_normal = d.template allocate_output<float>(0);
  d.end_stage(mark);
  return out;
}

}  // namespace keymesh::generate::device_structured
