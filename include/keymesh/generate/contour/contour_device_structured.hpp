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

// `value >= iso` at a grid point, as the sort plan's Classify tests it
// (mode 0 compare, 1 none inside, 2 all inside; NaN is outside).
template <class T>
struct Inside {
  const T* samples;
  T threshold;
  int mode;
  KEYMESH_HD bool operator()(Id q) const { return mode == 2 || (mode == 0 && samples[q] >= threshold); }
};

KEYMESH_HD inline unsigned count3(unsigned m) { return (m & 1u) + ((m >> 1) & 1u) + ((m >> 2) & 1u); }

// The grid and the inside test, as the row functors read them.
template <class T>
struct Rows {
  Inside<T> inside;
  Id nx, ny, nz, nxy;
  const MarchingCubesTable* table;

  // Bit a: the edge from grid point (i, j, k) along axis a is cut.
  KEYMESH_HD unsigned cut_edges(Id i, Id j, Id k) const {
    const Id p = i + nx * j + nxy * k;
    const bool in = inside(p);
    unsigned m = 0;
    if (i + 1 < nx && inside(p + 1) != in) m |= 1u;
    if (j + 1 < ny && inside(p + nx) != in) m |= 2u;
    if (k + 1 < nz && inside(p + nxy) != in) m |= 4u;
    return m;
  }
  // Voxel (i, j, k)'s cube case: bit c set when its corner c is inside.
  KEYMESH_HD unsigned cube_case(Id i, Id j, Id k) const {
    const Id p0 = i + nx * j + nxy * k;
    unsigned c = 0;
    for (int corner = 0; corner < 8; ++corner) {
      const Id q = p0 + (corner & 1) + nx * ((corner >> 1) & 1) + nxy * ((corner >> 2) & 1);
      c |= static_cast<unsigned>(inside(q)) << corner;
    }
    return c;
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
    std::uint64_t p = 0, t = 0;
    for (Id i = 0; i < g.nx; ++i) p += count3(g.cut_edges(i, j, k));
    if (g.has_voxels(j, k))
      for (Id i = 0; i + 1 < g.nx; ++i) t += g.table->triangle_count[g.cube_case(i, j, k)];
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
  const std::uint64_t* first;  // the isovalue's scan of CountRows' points
  Id base;                     // the isovalue's first point id
  Id iso;
  KEYMESH_HD void operator()(Id r) const {
    const Id j = r % g.ny, k = r / g.ny;
    Id id = base + static_cast<Id>(first[r]);
    for (Id i = 0; i < g.nx; ++i) {
      const unsigned m = g.cut_edges(i, j, k);
      for (int axis = 0; axis < 3; ++axis)
        if (m >> axis & 1u) out.write(interp, interp.at(i + g.nx * j + g.nxy * k, i, j, k, axis, iso), id++);
    }
  }
};

// Write: voxel row r's triangles, in voxel and table order (contour()'s).
// A corner's edge starts at grid point (i + dx, j + dy, k + dz): its id is
// that grid row's first, plus the row's cut edges before point i + dx, plus
// the point's cut edges along a smaller axis. The four grid rows' counts run
// along with i.
template <class T>
struct WriteRowTriangles {
  Rows<T> g;
  const std::uint64_t* point_first;
  const std::uint64_t* triangle_first;
  Id point_base, triangle_base;
  PointIndex* connectivity;
  KEYMESH_HD void operator()(Id r) const {
    const Id j = r % g.ny, k = r / g.ny;
    if (!g.has_voxels(j, k)) return;
    Id first[4], before[4] = {0, 0, 0, 0};
    unsigned here[4], next[4];  // cut edges at points i and i + 1 of each row
    for (int s = 0; s < 4; ++s) {
      const Id js = j + (s & 1), ks = k + (s >> 1);
      first[s] = point_base + static_cast<Id>(point_first[js + g.ny * ks]);
      here[s] = g.cut_edges(0, js, ks);
      next[s] = g.cut_edges(1, js, ks);
    }
    PointIndex* o = connectivity + 3 * (triangle_base + static_cast<Id>(triangle_first[r]));
    for (Id i = 0; i + 1 < g.nx; ++i) {
      const unsigned c = g.cube_case(i, j, k);
      const int corners = 3 * g.table->triangle_count[c];
      for (int n = 0; n < corners; ++n) {
        const CubeEdge& ce = g.table->edges[g.table->triangle_edges[c][n]];
        const int s = ce.dy + 2 * ce.dz;
        const unsigned lower = (1u << ce.axis) - 1u;
        const Id rank = ce.dx ? before[s] + count3(here[s]) + count3(next[s] & lower) : before[s] + count3(here[s] & lower);
        *o++ = static_cast<PointIndex>(first[s] + rank);
      }
      for (int s = 0; s < 4; ++s) {
        before[s] += count3(here[s]);
        here[s] = next[s];
        next[s] = i + 2 < g.nx ? g.cut_edges(i + 2, j + (s & 1), k + (s >> 1)) : 0u;
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
  const InsideTest<T> test(iso);
  const GridShape& s = in.shape;
  return Rows<T>{Inside<T>{in.samples, test.threshold, test.all ? 2 : (test.none ? 1 : 0)}, s.nx, s.ny, s.nz, s.nxy,
                 in.table.data()};
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
    ir.point_first = d.template allocate<std::uint64_t>(rows);
    ir.triangle_first = d.template allocate<std::uint64_t>(rows);
    auto mark = d.begin_stage(&st.classify);
    d.for_each(rows, CountRows<T>{rows_of(in, opt.isovalues[iso]), ir.point_first.data(), ir.triangle_first.data()});
    d.end_stage(mark);
    mark = d.begin_stage(&st.weld);
    ir.points = static_cast<Id>(d.exclusive_scan(ir.point_first.data(), ir.point_first.data(), rows));
    ir.triangles = static_cast<Id>(d.exclusive_scan(ir.triangle_first.data(), ir.triangle_first.data(), rows));
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
