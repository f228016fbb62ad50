#include "coarsen_slabs.hpp"

#include <algorithm>
#include <stdexcept>

#include "keymesh/generate/coarsen/coarsen.hpp"
#include "keymesh/generate/coarsen/coarsen_kernels.hpp"
#include "keymesh/generate/coarsen/split_nonmanifold.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/mesh/unused_points.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::generate {

namespace {

// A thin slab finishes a few thousand points: a parallel region for them
// costs more than the means (threads spin at its barrier).
constexpr Id kPointsPerTask = 1 << 15;

// coarsening::group_mean's arithmetic (summed in double from +0 in the
// group's order, divided by the count, rounded once) over a group whose
// members are numbered the carried points first, then the slab's.
float mean(const float* carried, const float* slab, Id num_carried, int k, int c, const std::uint32_t* order, Id b,
           Id e) {
  double s = 0;
  for (Id j = b; j < e; ++j) {
    const Id p = order[j];
    s += p < num_carried ? carried[p * k + c] : slab[(p - num_carried) * k + c];
  }
  return static_cast<float>(s / static_cast<double>(e - b));
}

}  // namespace

// One isovalue's points of a slab: [begin, end) of the slab's fine points.
struct SlabCoarsening::SlabRange {
  const SurfaceMesh& fine;
  const std::vector<std::uint64_t>& keys;
  const std::vector<std::uint64_t>& nearest;
  Id begin, end;
  Id k0, k_last;
  bool last;
  Id iso_index;
};

SlabCoarsening::SlabCoarsening(const Id dims[3], Id isovalues)
    : nxy_(dims[0] * dims[1]), points_per_iso_(dims[0] * dims[1] * dims[2]),
      isos_(static_cast<std::size_t>(isovalues)) {}

Id SlabCoarsening::plane_of(std::uint64_t coarse_key) const {
  return static_cast<Id>(coarse_key % static_cast<std::uint64_t>(points_per_iso_)) / nxy_;
}

void SlabCoarsening::take_fields(const SurfaceMesh& fine) {
  if (have_fields_) return;
  for (const Field& f : fine.point_fields) field_shapes_.push_back(Field{f.name, f.components, {}});
  for (Isovalue& iso : isos_) {
    iso.fields.resize(field_shapes_.size());
    iso.carried.fields.resize(field_shapes_.size());
  }
  have_fields_ = true;
}

void SlabCoarsening::add_slab(const SurfaceMesh& fine, const std::vector<std::uint64_t>& keys,
                              const std::vector<std::uint64_t>& nearest, Id k0, Id k_last, bool last) {
  if (!std::is_sorted(keys.begin(), keys.end()))
    throw std::logic_error("SlabCoarsening: a slab's fine points must come in edge-key order");
  take_fields(fine);
  Id held = static_cast<Id>(keys.size());
  for (const Isovalue& iso : isos_) held += iso.carried.size();
  most_held_ = std::max(most_held_, held);
  const std::uint64_t per_iso = 3 * static_cast<std::uint64_t>(points_per_iso_);
  for (std::size_t i = 0; i < isos_.size(); ++i) {
    Isovalue& iso = isos_[i];
    iso.previous = std::move(iso.current);
    iso.current = Finished{{}, static_cast<Id>(iso.xyz.size() / 3)};
    const Id begin = std::lower_bound(keys.begin(), keys.end(), i * per_iso) - keys.begin();
    const Id end = std::lower_bound(keys.begin(), keys.end(), (i + 1) * per_iso) - keys.begin();
    finish_points(iso, SlabRange{fine, keys, nearest, begin, end, k0, k_last, last, static_cast<Id>(i)});
  }
  for (Isovalue& iso : isos_) number_waiting(iso);
  add_triangles(fine, keys, nearest, k_last, last);
  for (std::size_t i = 0; i < isos_.size(); ++i) decide_folds(isos_[i], static_cast<Id>(i), k_last, last);
}

// Groups the carried crossings and the slab's by coarse key (KEY-REDUCE,
// dense over the slab's planes; members in edge-key order), finishes the
// groups below the last plane (a prefix: keys ascend plane by plane) and
// carries the last plane's crossings from z edges below it.
void SlabCoarsening::finish_points(Isovalue& iso, const SlabRange& s) {
  const FinePoints& carried = iso.carried;
  const Id nc = carried.size(), n = nc + (s.end - s.begin);
  const std::uint64_t first = static_cast<std::uint64_t>(s.iso_index * points_per_iso_ + s.k0 * nxy_);
  std::vector<std::uint64_t> relative(static_cast<std::size_t>(n));
  for (Id j = 0; j < nc; ++j) relative[j] = carried.nearest[j] - first;
  for (Id j = nc; j < n; ++j) relative[j] = s.nearest[s.begin + j - nc] - first;
  const auto g = keyreduce::partition_dense(relative.data(), n,
                                            static_cast<std::uint64_t>((s.k_last - s.k0 + 1) * nxy_),
                                            keyreduce::Order::Build);
  std::vector<std::uint64_t>().swap(relative);
  const Id groups = g.num_groups();
  Id done = groups;
  if (!s.last)
    while (done > 0 && plane_of(g.unique_keys[done - 1] + first) == s.k_last) --done;
  // Means of the finished groups, appended after the points finished before.
  const Id at = static_cast<Id>(iso.xyz.size() / 3);
  iso.xyz.resize(static_cast<std::size_t>(3 * (at + done)));
  parallel::for_each(done, [&](Id p) {
    for (int c = 0; c < 3; ++c)
      iso.xyz[3 * (at + p) + c] = mean(carried.xyz.data(), s.fine.points.data() + 3 * s.begin, nc, 3, c,
                                       g.order.data(), g.offsets[p], g.offsets[p + 1]);
  }, kPointsPerTask);
  for (std::size_t f = 0; f < field_shapes_.size(); ++f) {
    const int k = field_shapes_[f].components;
    Array<float>& dst = iso.fields[f];
    dst.resize(static_cast<std::size_t>(k * (at + done)));
    const bool normals = field_shapes_[f].name == "Normals" && k == 3;
    parallel::for_each(done, [&](Id p) {
      for (int c = 0; c < k; ++c)
        dst[k * (at + p) + c] = mean(carried.fields[f].data(), s.fine.point_fields[f].values.data() + k * s.begin, nc,
                                     k, c, g.order.data(), g.offsets[p], g.offsets[p + 1]);
      if (normals) coarsening::renormalize(&dst[3 * (at + p)]);
    }, kPointsPerTask);
  }
  iso.current.keys.resize(static_cast<std::size_t>(done));
  for (Id p = 0; p < done; ++p) iso.current.keys[p] = g.unique_keys[p] + first;
  fine_points_ += g.offsets[done];
  // The last plane's crossings from the z edges below it: the next slab
  // brings its x and y edges again and its upper z edges.
  FinePoints next;
  next.fields.resize(field_shapes_.size());
  const std::uint64_t per_iso = 3 * static_cast<std::uint64_t>(points_per_iso_);
  for (Id j = g.offsets[done]; j < g.offsets[groups]; ++j) {
    const Id q = s.begin + g.order[j] - nc;  // never a carried point: those lie on plane k0 < k_last
    if (static_cast<Id>(s.keys[q] % per_iso / 3) / nxy_ == s.k_last) continue;
    next.nearest.push_back(s.nearest[q]);
    next.xyz.insert(next.xyz.end(), s.fine.points.begin() + 3 * q, s.fine.points.begin() + 3 * q + 3);
    for (std::size_t f = 0; f < field_shapes_.size(); ++f) {
      const int k = field_shapes_[f].components;
      const auto& values = s.fine.point_fields[f].values;
      next.fields[f].insert(next.fields[f].end(), values.begin() + k * q, values.begin() + k * q + k);
    }
  }
  iso.carried = std::move(next);
}

// Every fine triangle, in order, as local ids when its points are finished
// and none waits before it, or else as its points' coarse keys, to wait for
// the next slab (only the last voxel layer's do); collapsed ones dropped
// (coarsen()'s rule).
void SlabCoarsening::add_triangles(const SurfaceMesh& fine, const std::vector<std::uint64_t>& keys,
                                   const std::vector<std::uint64_t>& nearest, Id k_last, bool last) {
  const std::uint64_t per_iso = 3 * static_cast<std::uint64_t>(points_per_iso_);
  const Id n = fine.num_cells();
  fine_triangles_ += n;
  for (Id t = 0; t < n; ++t) {
    const PointIndex* c = &fine.connectivity[3 * t];
    const std::uint64_t k[3] = {nearest[c[0]], nearest[c[1]], nearest[c[2]]};
    if (k[0] == k[1] || k[1] == k[2] || k[0] == k[2]) continue;
    Isovalue& iso = isos_[static_cast<std::size_t>(keys[c[0]] / per_iso)];
    const bool finished =
        last || (plane_of(k[0]) < k_last && plane_of(k[1]) < k_last && plane_of(k[2]) < k_last);
    if (finished && iso.waiting.empty())
      for (std::uint64_t key : k) iso.triangles.push_back(local_id(iso, key));
    else
      iso.waiting.insert(iso.waiting.end(), {k[0], k[1], k[2]});
  }
}

// The triangles that waited for this slab: their points are finished now
// (planes k0 - 1 and k0 of this slab).
void SlabCoarsening::number_waiting(Isovalue& iso) const {
  for (std::uint64_t key : iso.waiting) iso.triangles.push_back(local_id(iso, key));
  iso.waiting.clear();
}

// Folds: a set of equal triangles lies in the voxel layers around its
// points, so a set whose points all lie below plane k_last - 1 came from
// layers that are read and whose triangles are all numbered (only the last
// layer's wait). Those sets are decided; the others are looked at again
// after the next slab (coarsen.hpp, remove_complete_folds).
void SlabCoarsening::decide_folds(Isovalue& iso, Id iso_index, Id k_last, bool last) const {
  PointIndex complete_below = static_cast<PointIndex>(iso.xyz.size() / 3);
  if (!last) {
    const std::uint64_t plane = static_cast<std::uint64_t>(iso_index * points_per_iso_ + (k_last - 1) * nxy_);
    const auto& keys = iso.current.keys;
    complete_below = static_cast<PointIndex>(iso.current.base + (std::lower_bound(keys.begin(), keys.end(), plane) -
                                                                 keys.begin()));
  }
  iso.fold_from = remove_complete_folds(iso.triangles, iso.fold_from, complete_below);
}

// A waiting triangle's points were finished by this slab or the one before.
PointIndex SlabCoarsening::local_id(const Isovalue& iso, std::uint64_t key) const {
  for (const Finished* f : {&iso.current, &iso.previous}) {
    const auto it = std::lower_bound(f->keys.begin(), f->keys.end(), key);
    if (it != f->keys.end() && *it == key) return static_cast<PointIndex>(f->base + (it - f->keys.begin()));
  }
  throw std::logic_error("SlabCoarsening: a triangle's coarse point was not finished by the last two slabs");
}

// The isovalues' points and triangles one after the other, as coarsen()
// numbers them (its keys put isovalue i's grid points after i - 1's).
SurfaceMesh SlabCoarsening::assemble() {
  SurfaceMesh out;
  out.point_fields = field_shapes_;
  if (isos_.size() == 1) {
    out.points = std::move(isos_[0].xyz);
    for (std::size_t f = 0; f < field_shapes_.size(); ++f) out.point_fields[f].values = std::move(isos_[0].fields[f]);
    out.connectivity = std::move(isos_[0].triangles);
    return out;
  }
  PointIndex base = 0;
  for (Isovalue& iso : isos_) {
    out.points.insert(out.points.end(), iso.xyz.begin(), iso.xyz.end());
    for (std::size_t f = 0; f < field_shapes_.size(); ++f)
      out.point_fields[f].values.insert(out.point_fields[f].values.end(), iso.fields[f].begin(), iso.fields[f].end());
    for (PointIndex p : iso.triangles) out.connectivity.push_back(base + p);
    base += static_cast<PointIndex>(iso.xyz.size() / 3);
    iso = Isovalue{};
  }
  return out;
}

SurfaceMesh SlabCoarsening::finish() {
  for (const Isovalue& iso : isos_)
    if (!iso.waiting.empty() || iso.carried.size() != 0)
      throw std::logic_error("SlabCoarsening::finish before the last slab");
  SurfaceMesh out = assemble();
  remove_points(out, split_nonmanifold(out).unused);
  return out;
}

}  // namespace keymesh::generate
