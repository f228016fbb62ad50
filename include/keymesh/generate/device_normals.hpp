#pragma once
// Averaged point normals on a device (the generators' device paths): face
// normals per triangle, summed per point by a segmented reduce in a fixed
// order (mesh/normals.hpp's merge: add, from zero), then made unit. The
// arithmetic is mesh/face_normal.hpp's, the CPU's.
#include <cstdint>

#include "keymesh/core/device.hpp"
#include "keymesh/core/types.hpp"
#include "keymesh/device/algorithms.hpp"
#include "keymesh/mesh/face_normal.hpp"

namespace keymesh::generate::device_normals {

struct Faces {
  const float* xyz;
  const PointIndex* triangles;
  Vec3f* face;
  KEYMESH_HD void operator()(Id t) const { face[t] = triangle_normal(xyz, triangles, t); }
};

struct Add {
  KEYMESH_HD Vec3f operator()(Vec3f a, Vec3f b) const { return add(a, b); }
};

struct Unit {
  Vec3f* v;
  KEYMESH_HD void operator()(Id i) const { v[i] = unit(v[i]); }
};

// The face normal of every triangle.
template <class D>
typename D::template Array<Vec3f> face_normals(const D& d, const float* xyz, const PointIndex* triangles, Id count) {
  auto face = d.template allocate<Vec3f>(count);
  d.for_each(count, Faces{xyz, triangles, face.data()});
  return face;
}

// 3 floats per point, zero: the sums a segmented reduce with Add fills, made
// unit in place: the generator's normals field (allocate_output).
template <class D>
typename D::template Array<float> zero_sums(const D& d, Id points) {
  auto sums = d.template allocate_output<float>(3 * points);
  device::fill(d, reinterpret_cast<Vec3f*>(sums.data()), points, Vec3f{0, 0, 0});
  return sums;
}

template <class D>
void make_unit(const D& d, float* sums, Id points) {
  d.for_each(points, Unit{reinterpret_cast<Vec3f*>(sums)});
}

}  // namespace keymesh::generate::device_normals
