#include "keymesh/mesh/normals.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/core/uninitialized_array.hpp"
#include "keymesh/parallel/fresh_memory.hpp"

namespace keymesh {

namespace {
void require_triangles(const SurfaceMesh& mesh) {
  if (!mesh.all_triangles()) throw InputError("normals: the mesh has polygons; only triangles are averaged");
}
}  // namespace

std::vector<Vec3f> face_normals(const SurfaceMesh& mesh) {
  require_triangles(mesh);
  std::vector<Vec3f> face(static_cast<std::size_t>(mesh.num_cells()));
  const float* P = mesh.points.data();
  const PointIndex* C = mesh.connectivity.data();
  parallel::for_each(mesh.num_cells(), [&](Id t) { face[t] = triangle_normal(P, C, t); });
  return face;
}

void sum_point_normals(const SurfaceMesh& mesh, Vec3f* out) {
  require_triangles(mesh);
  const float* P = mesh.points.data();
  const PointIndex* C = mesh.connectivity.data();
  const Id triangles = mesh.num_cells(), points = mesh.num_points();
  const int chunks = parallel::chunk_count(triangles);
  if (chunks <= 1) {
    std::fill_n(out, points, Vec3f{0, 0, 0});
    for (Id t = 0; t < triangles; ++t) {
      const Vec3f f = triangle_normal(P, C, t);
      for (Id c = 3 * t; c < 3 * t + 3; ++c) out[C[c]] = add(out[C[c]], f);
    }
    return;
  }
  // The serial scatter's order kept with the triangles cut into chunks,
  // one a thread: each point's first chunk (the lowest that names it) adds
  // its corners there, in order, while later chunks set theirs aside; the
  // set-aside corners are then added chunk after chunk. A contour's
  // triangles come in row order, so only the points along the cuts between
  // chunks are set aside (a mesh in random order sets most aside and runs
  // at the serial scatter's speed, with the same bytes).
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  const std::unique_ptr<std::uint32_t[]> first = uninitialized_array<std::uint32_t>(static_cast<std::size_t>(points));
  parallel::for_each(points, [&](Id p) { out[p] = Vec3f{0, 0, 0}, first[p] = kNone; });
  parallel::for_each_chunk(triangles, chunks, [&](Id begin, Id end, int chunk) {
    const auto me = static_cast<std::uint32_t>(chunk);
    for (Id c = 3 * begin; c < 3 * end; ++c) {
      std::atomic_ref<std::uint32_t> at(first[C[c]]);
      std::uint32_t seen = at.load(std::memory_order_relaxed);
      while (me < seen && !at.compare_exchange_weak(seen, me, std::memory_order_relaxed)) {
      }
    }
  });
  struct SetAside {
    PointIndex point;
    Vec3f normal;
  };
  std::vector<std::vector<SetAside>> set_aside(static_cast<std::size_t>(chunks));
  parallel::for_each_chunk(triangles, chunks, [&](Id begin, Id end, int chunk) {
    const auto me = static_cast<std::uint32_t>(chunk);
    std::vector<SetAside>& later = set_aside[static_cast<std::size_t>(chunk)];
    for (Id t = begin; t < end; ++t) {
      const Vec3f f = triangle_normal(P, C, t);
      for (Id c = 3 * t; c < 3 * t + 3; ++c) {
        const PointIndex p = C[c];
        if (first[p] == me) out[p] = add(out[p], f);
        else later.push_back({p, f});
      }
    }
  });
  for (const std::vector<SetAside>& later : set_aside)
    for (const SetAside& a : later) out[a.point] = add(out[a.point], a.normal);
}

std::vector<Vec3f> point_normal_sums(const SurfaceMesh& mesh) {
  std::vector<Vec3f> sums(static_cast<std::size_t>(mesh.num_points()));
  sum_point_normals(mesh, sums.data());
  return sums;
}

void normalize(Vec3f* v, Id n) {
  parallel::for_each(n, [&](Id i) { v[i] = unit(v[i]); });
}

Field normals_field(const std::vector<Vec3f>& v) {
  Field n{"Normals", 3, Array<float>(3 * v.size())};
  std::copy_n(reinterpret_cast<const float*>(v.data()), n.values.size(), n.values.data());
  return n;
}

void average_normals(SurfaceMesh& mesh) {
  // Summed and normalised in the field's own array, written once (no copy).
  Field n{"Normals", 3, {}};
  parallel::resize_fresh(n.values, static_cast<std::size_t>(3 * mesh.num_points()));
  auto* v = reinterpret_cast<Vec3f*>(n.values.data());
  sum_point_normals(mesh, v);
  normalize(v, mesh.num_points());
  for (Field& f : mesh.point_fields)
    if (f.name == "Normals") {
      f = std::move(n);
      return;
    }
  mesh.point_fields.push_back(std::move(n));
}

}  // namespace keymesh
