#pragma once
// The face normal and its merge and transform, as plain device-friendly
// functions (no allocation, KEYMESH_HD): the CPU generators and the CUDA
// backend compute the same bits. Point normals: mesh/normals.hpp.
#include <cmath>

#include "keymesh/core/device.hpp"
#include "keymesh/core/types.hpp"

namespace keymesh {

struct Vec3f {
  float x, y, z;
};

// Twice the area times the unit normal of triangle t (float arithmetic;
// KEYMESH_HD: the CUDA backend computes the same bits).
KEYMESH_HD inline Vec3f triangle_normal(const float* P, const PointIndex* C, Id t) {
  const float* a = P + 3 * Id{C[3 * t]};
  const float* b = P + 3 * Id{C[3 * t + 1]};
  const float* c = P + 3 * Id{C[3 * t + 2]};
  const float u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const float v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  return Vec3f{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}

// The merge of point normals.
KEYMESH_HD inline Vec3f add(Vec3f a, Vec3f b) { return Vec3f{a.x + b.x, a.y + b.y, a.z + b.z}; }

// The transform: the unit vector of s, or zero.
KEYMESH_HD inline Vec3f unit(Vec3f s) {
  const float len = std::sqrt(s.x * s.x + s.y * s.y + s.z * s.z);
  return len > 0 ? Vec3f{s.x / len, s.y / len, s.z / len} : Vec3f{0, 0, 0};
}

}  // namespace keymesh
