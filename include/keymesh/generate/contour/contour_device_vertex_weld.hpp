#pragma once
// Marching cubes on a voxel grid over the device layer, welded by VERTEX-WELD
// (the paper's Table 2 baseline; Bell's weld_vertices, keymesh/weld/vertex_weld.hpp
// on the CPU): the sort plan's soup of edge keys (contour_device.hpp), a
// position per corner, three stable radix sorts of the coordinates' order-
// preserving bits (z, then y, then x), one point per run of equal coordinates
// (-0 equals +0; the point keeps its run's first corner's bits), every corner
// mapped to its run. The fields come from the key of each run's first corner,
// averaged normals from the points' corners in increasing order, from zero:
// contour(..., weld VertexWeld)'s arithmetic and order, so its bytes.
#include <cstdint>
#include <cstring>
#include <utility>

#include "keymesh/core/device.hpp"
#include "keymesh/device/algorithms.hpp"
#include "keymesh/device/key_groups.hpp"
#include "keymesh/generate/contour/contour_device.hpp"

namespace keymesh::generate::device_vertex_weld {

// A float's bits as an unsigned integer of the same order (-0 as +0), as
// vertex_weld.cpp's sortable_bits.
KEYMESH_HD inline std::uint32_t sortable_bits(float f) {
  if (f == 0.0f) f = 0.0f;
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

// Corner c's position, from its edge key (the CPU's weld position callback).
template <class T, class K>
struct CornerPositions {
  EdgeInterpolator<T> interp;
  const K* keys;
  float* xyz;
  KEYMESH_HD void operator()(Id c) const {
    interp.position(interp.locate(static_cast<std::uint64_t>(keys[c])), xyz + 3 * c);
  }
};

struct AxisBits {
  const float* xyz;
  const std::uint32_t* perm;
  int axis;
  std::uint32_t* bits;
  KEYMESH_HD void operator()(Id i) const { bits[i] = sortable_bits(xyz[3 * static_cast<Id>(perm[i]) + axis]); }
};

// Whether sorted positions i and i - 1 hold different coordinates (or i = 0).
struct RunHead {
  const float* xyz;
  const std::uint32_t* perm;
  KEYMESH_HD bool operator()(Id i) const {
    if (i == 0) return true;
    const float* p = xyz + 3 * static_cast<Id>(perm[i]);
    const float* q = xyz + 3 * static_cast<Id>(perm[i - 1]);
    return !(p[0] == q[0] && p[1] == q[1] && p[2] == q[2]);
  }
};

struct Heads {
  RunHead head;
  Id* out;
  KEYMESH_HD void operator()(Id i) const { out[i] = head(i) ? 1 : 0; }
};

// Every corner's point (the index map: the triangle list); every point's
// first corner (the stable sorts put the smallest corner first) and its
// coordinates, that corner's bits.
struct WriteRuns {
  RunHead head;
  const Id* rank;  // exclusive scan of Heads
  std::uint32_t* index_map;
  std::uint32_t* first;
  float* points;
  KEYMESH_HD void operator()(Id i) const {
    const bool h = head(i);
    const Id r = h ? rank[i] : rank[i] - 1;
    const Id c = perm()[i];
    index_map[c] = static_cast<std::uint32_t>(r);
    if (!h) return;
    first[r] = static_cast<std::uint32_t>(c);
    for (int a = 0; a < 3; ++a) points[3 * r + a] = head.xyz[3 * c + a];
  }
  KEYMESH_HD const std::uint32_t* perm() const { return head.perm; }
};

// Point g's fields (not its position: the welded coordinates) from its
// first corner's key.
template <class T, class K>
struct WriteWeldedFields {
  EdgeInterpolator<T> interp;
  const K* keys;
  const std::uint32_t* first;
  device_contour::PointOutputs<T> out;
  KEYMESH_HD void operator()(Id g) const {
    out.write(interp, interp.locate(static_cast<std::uint64_t>(keys[first[g]])), g);
  }
};

// The weld of the soup's corners: the points, their first corners, the index map.
template <class D>
struct Welded {
  typename D::template Array<float> points;
  typename D::template Array<std::uint32_t> first, index_map;
  Id count = 0;
};

template <class D>
Welded<D> weld_positions(const D& d, const float* xyz, Id n) {
  auto perm = d.template allocate<std::uint32_t>(n);
  device::iota(d, perm.data(), n);
  {
    auto bits = d.template allocate<std::uint32_t>(n);
    for (int axis = 2; axis >= 0; --axis) {
      d.for_each(n, AxisBits{xyz, perm.data(), axis, bits.data()});
      d.sort_pairs(bits.data(), perm.data(), n, 32);
    }
  }
  const RunHead head{xyz, perm.data()};
  auto rank = d.template allocate<Id>(n);
  d.for_each(n, Heads{head, rank.data()});
  Welded<D> w;
  w.count = static_cast<Id>(d.exclusive_scan(rank.data(), rank.data(), n));
  w.points = d.template allocate_output<float>(3 * w.count);
  w.first = d.template allocate<std::uint32_t>(w.count);
  w.index_map = d.template allocate_output<std::uint32_t>(n);
  d.for_each(n, WriteRuns{head, rank.data(), w.index_map.data(), w.first.data(), w.points.data()});
  return w;
}

// Averaged normals over VERTEX-WELD's groups: each point's corners in
// increasing order (a stable sort of the index map), face normals summed
// from zero (the sort plan's averaged_normals with a single block).
template <class D, class K>
typename D::template Array<float> averaged_normals(const D& d, const device_contour::ContourArrays<D>& out) {
  const Id corners = 3 * out.triangles;
  device_contour::Soup<D, std::uint32_t> soup{d.template allocate<std::uint32_t>(corners), d.template allocate<Id>(2),
                                              corners};
  device::fill(d, soup.blocks.data(), 1, Id{0});
  device::fill(d, soup.blocks.data() + 1, 1, corners);
  device::copy(d, out.connectivity.data(), corners, soup.keys.data());
  int bits = 0;
  while (bits < 32 && (static_cast<std::uint64_t>(out.points - 1) >> bits) != 0) ++bits;
  const auto g = device::group_keys(d, soup.keys.data(), corners, bits);
  return device_contour::averaged_normals(d, g, soup, out.xyz.data(), out.connectivity.data());
}

template <class D, class K, class T>
device_contour::ContourArrays<D> contour_arrays(const D& d, const device_contour::Input<D, T>& in,
                                                const ContourOptions& opt, ContourStats& st) {
  st.key_bits = static_cast<int>(sizeof(K) * 8);
  device_contour::Soup<D, K> soup = device_contour::emit_soup<D, K>(d, in, opt, st);
  st.soup_points = soup.corners;
  const Id n = soup.corners;
  const EdgeInterpolator<T> interp{in.samples, in.shape, in.isovalues.data(), 3 * in.shape.n};
  auto mark = d.begin_stage(&st.weld);
  Welded<D> w;
  {
    auto xyz = d.template allocate<float>(3 * n);
    d.for_each(n, CornerPositions<T, K>{interp, soup.keys.data(), xyz.data()});
    w = weld_positions(d, xyz.data(), n);
  }
  d.end_stage(mark);
  device_contour::ContourArrays<D> out;
  out.points = w.count;
  out.triangles = n / 3;
  check_contour_output(opt, out.points, out.triangles);
  mark = d.begin_stage(&st.fields);
  out.xyz = std::move(w.points);
  out.connectivity = std::move(w.index_map);
  d.for_each(out.points, WriteWeldedFields<T, K>{interp, soup.keys.data(), w.first.data(),
                                                 device_contour::point_outputs<T>(d, out, opt, false)});
  if (opt.normals == ContourNormals::Average)
    out.fields.averaged_normal =
        n > 0 ? averaged_normals<D, K>(d, out) : d.template allocate_output<float>(0);
  d.end_stage(mark);
  return out;
}

}  // namespace keymesh::generate::device_vertex_weld
