#include "keymesh/generate/contour/contour_stream.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <array>
#include <random>
#include <set>

#include "keymesh/analyze/topology.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "uniform_noise.hpp"

using namespace keymesh;
using generate::ContourOptions;

namespace {

// Planes served from a grid held in memory (the test's stand-in for a file).
class GridPlanes : public PlaneSource {
 public:
  explicit GridPlanes(const ImageGrid& g) : g_(g) {
    head_.dims = g.dims, head_.type = g.type, head_.spacing = g.spacing, head_.origin = g.origin, head_.name = g.name;
  }
  const ImageGrid& header() const override { return head_; }
  void read_planes(Id first, Id count, std::byte* out) override {
    const std::size_t plane = static_cast<std::size_t>(g_.dims[0] * g_.dims[1]) * scalar_size(g_.type);
    std::memcpy(out, g_.bytes.data() + plane * static_cast<std::size_t>(first), plane * static_cast<std::size_t>(count));
    ++reads;
  }
  int reads = 0;

 private:
  const ImageGrid& g_;
  ImageGrid head_;
};

void expect_same(const SurfaceMesh& a, const SurfaceMesh& b) {
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_EQ(std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(float)), 0);
  EXPECT_EQ(a.connectivity, b.connectivity);
  ASSERT_EQ(a.point_fields.size(), b.point_fields.size());
  for (std::size_t i = 0; i < a.point_fields.size(); ++i) EXPECT_EQ(a.point_fields[i].values, b.point_fields[i].values);
}

TEST(ContourStream, SlabsGiveTheWholeVolumesMeshBitForBit) {
  ImageGrid g = generate::spherical_distance(40);
  g.origin = {-3.5, 2.25, 10.125};
  g.spacing = {0.5, 1.5, 0.3};
  ContourOptions o;
  o.isovalues = {17.25, 9.5};
  const SurfaceMesh whole = generate::contour(g, o);
  const std::size_t plane = 40 * 40 * sizeof(float);
  for (std::size_t planes : {2u, 3u, 7u, 39u, 40u, 100u}) {
    GridPlanes src(g);
    generate::StreamStats ss;
    const SurfaceMesh m = generate::contour_streamed(src, o, planes * plane, nullptr, &ss);
    expect_same(whole, m);
    EXPECT_LE(ss.slab_bytes, planes * plane);
    EXPECT_EQ(ss.slabs, src.reads);
  }
}

TEST(ContourStream, IntegerSamplesAndRefusals) {
  ImageGrid g;
  g.allocate({17, 23, 31}, ScalarType::UInt16);
  std::mt19937 rng(2);
  auto* v = reinterpret_cast<std::uint16_t*>(g.data());
  for (Id p = 0; p < g.num_points(); ++p) v[p] = static_cast<std::uint16_t>(rng() % 1000);
  ContourOptions o;
  o.isovalues = {500.5};
  GridPlanes src(g);
  expect_same(generate::contour(g, o), generate::contour_streamed(src, o, 5 * 17 * 23 * 2));
  EXPECT_THROW(generate::contour_streamed(src, o, 17 * 23 * 2), LimitError);  // one plane only
  o.normals = generate::ContourNormals::Gradient;
  EXPECT_THROW(generate::contour_streamed(src, o, 3 * 17 * 23 * 2), LimitError);  // 1 plane + 2 ghosts
}

// Averaged normals: a shared point's partial sums from two slabs are added
// by the merge. Points and triangles bit for bit; normals within rounding of
// the in-memory sums (another summation order), unit length. A merge that
// kept one slab's sum only would tilt the border normals far more.
TEST(ContourStream, AveragedNormalsMergeAcrossSlabs) {
  const ImageGrid g = generate::spherical_distance(40);
  ContourOptions o;
  o.isovalues = {17.25, 9.5};
  o.normals = generate::ContourNormals::Average;
  const SurfaceMesh whole = generate::contour(g, o);
  const std::size_t plane = 40 * 40 * sizeof(float);
  for (std::size_t planes : {2u, 5u, 40u}) {
    GridPlanes src(g);
    const SurfaceMesh m = generate::contour_streamed(src, o, planes * plane);
    ASSERT_EQ(m.points, whole.points);
    ASSERT_EQ(m.connectivity, whole.connectivity);
    ASSERT_EQ(m.point_fields.size(), 2u);
    EXPECT_EQ(m.point_fields[1].name, "Normals");
    const auto& a = m.point_fields[1].values;
    const auto& b = whole.point_fields[1].values;
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) ASSERT_NEAR(a[i], b[i], 1e-6) << i;
    for (std::size_t p = 0; p < a.size(); p += 3)
      ASSERT_NEAR(a[p] * a[p] + a[p + 1] * a[p + 1] + a[p + 2] * a[p + 2], 1.0, 1e-5) << p / 3;
  }
}

// Gradient normals and curvature read a ghost plane on either side of each
// slab: the fields are bit for bit those of the whole volume, on noise (every
// case, large gradients) at every slab size down to two planes.
TEST(ContourStream, GhostPlanesGiveTheWholeVolumesDerivatives) {
  ImageGrid g;
  g.allocate({13, 11, 17}, ScalarType::Float32);
  g.spacing = {0.5, 2.0, 0.75};
  std::mt19937 rng(5);
  auto* v = reinterpret_cast<float*>(g.data());
  for (Id p = 0; p < g.num_points(); ++p) v[p] = static_cast<float>(rng() % 1000) * 0.01f;
  ContourOptions o;
  o.isovalues = {4.995, 2.5};
  o.normals = generate::ContourNormals::Gradient;
  o.curvature = true;
  const SurfaceMesh whole = generate::contour(g, o);
  ASSERT_EQ(whole.point_fields.size(), 3u);  // scalars, Normals, mean_curvature
  const std::size_t plane = 13 * 11 * sizeof(float);
  for (std::size_t planes : {4u, 5u, 8u, 19u}) {
    GridPlanes src(g);
    generate::StreamStats ss;
    expect_same(whole, generate::contour_streamed(src, o, planes * plane, nullptr, &ss));
    EXPECT_LE(ss.slab_bytes, planes * plane);
  }
  // The same slab contoured without its ghosts differs at the border.
  GridPlanes src(g);
  auto planes_of = [&](Id first, Id count) {
    ImageGrid slab;
    slab.spacing = g.spacing;
    slab.allocate({13, 11, count}, g.type);
    src.read_planes(first, count, slab.bytes.data());
    return slab;
  };
  const ImageGrid slab = planes_of(5, 6), ghosted = planes_of(4, 8);
  ContourOptions bare = o;
  bare.first_plane = 5;
  bare.total_planes = 17;
  ContourOptions with = o;
  with.first_plane = 4;
  with.total_planes = 17;
  with.ghost_below = with.ghost_above = 1;
  const SurfaceMesh a = generate::contour(slab, bare), b = generate::contour(ghosted, with);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.connectivity, b.connectivity);
  EXPECT_NE(a.point_fields[1].values, b.point_fields[1].values);
  with.ghost_below = 2;
  EXPECT_THROW(generate::contour(ghosted, with), InputError);
}

}  // namespace

// Coarsening streamed: the slabs' fine points merged by edge key, then
// coarsened by nearest grid point, give the in-memory coarse mesh bit for
// bit (averaged normals too: computed from the coarse mesh either way), for
// slabs of every size, several isovalues and every field option. The noise's
// border samples are 0, below both isovalues, so that every surface is
// closed: a triangle lost or doubled at a slab border shows as a boundary
// edge, and the counts checked are of real surfaces (thousands of coarse
// triangles, fewer than the fine ones), not of two empty meshes.
TEST(ContourStream, CoarseningStreamedEqualsInMemory) {
  ImageGrid g = keymesh::testing::uniform_noise({37, 29, 23}, 9, 0, 1);
  float* v = static_cast<float*>(g.data());
  for (Id k = 0; k < 23; ++k)
    for (Id j = 0; j < 29; ++j)
      for (Id i = 0; i < 37; ++i)
        if (i == 0 || j == 0 || k == 0 || i == 36 || j == 28 || k == 22) v[i + 37 * (j + 29 * k)] = 0;
  g.spacing = {0.5, 1.25, 2.0};
  g.origin = {-3, 1, 7};
  const std::size_t plane = 37 * 29 * sizeof(float);
  for (auto normals : {generate::ContourNormals::None, generate::ContourNormals::Gradient,
                       generate::ContourNormals::Average}) {
    ContourOptions o;
    o.isovalues = {0.5, 0.31};
    o.normals = normals;
    o.curvature = normals == generate::ContourNormals::Gradient;
    o.coarsen = true;
    generate::ContourStats whole_stats;
    const SurfaceMesh whole = generate::contour(g, o, &whole_stats);
    ASSERT_GT(whole.num_cells(), 2000);
    EXPECT_GT(whole_stats.triangles_before_coarsening, whole.num_cells());
    EXPECT_EQ(analyze::check_fans(whole).boundary_edges, 0);
    for (std::size_t planes : {4u, 5u, 11u, 23u}) {
      GridPlanes src(g);
      generate::ContourStats st;
      const SurfaceMesh m = generate::contour_streamed(src, o, planes * plane, &st);
      SCOPED_TRACE("planes " + std::to_string(planes) + " normals " + std::to_string(static_cast<int>(normals)));
      ASSERT_EQ(m.num_cells(), whole.num_cells());
      ASSERT_EQ(m.num_points(), whole.num_points());
      expect_same(whole, m);
      EXPECT_EQ(analyze::check_fans(m).boundary_edges, 0);
      EXPECT_EQ(st.triangles_before_coarsening, whole_stats.triangles_before_coarsening);
    }
  }
}

// A box of the grid contoured on its own with position_offset (a Dask
// chunk's task, python/src/dask_contour_block.cpp) gives its points the
// bits of the whole grid's: every box point is a whole-grid point.
TEST(ContourStream, BoxWithPositionOffsetGivesTheWholeGridsPositions) {
  ImageGrid g = generate::spherical_distance(30);
  g.origin = {-3.5, 2.25, 10.125};
  g.spacing = {0.5, 1.5, 0.3};
  ContourOptions o;
  o.isovalues = {9.75};
  const SurfaceMesh whole = generate::contour(g, o);
  const Id first[3] = {7, 11, 5}, dims[3] = {9, 6, 13};
  ImageGrid box;
  box.spacing = g.spacing, box.origin = g.origin;
  box.allocate({dims[0], dims[1], dims[2]}, g.type);
  for (Id k = 0; k < dims[2]; ++k)
    for (Id j = 0; j < dims[1]; ++j)
      std::memcpy(box.bytes.data() + sizeof(float) * static_cast<std::size_t>(dims[0] * (j + dims[1] * k)),
                  g.bytes.data() + sizeof(float) * static_cast<std::size_t>(first[0] + 30 * (first[1] + j + 30 * (first[2] + k))),
                  sizeof(float) * static_cast<std::size_t>(dims[0]));
  for (int a = 0; a < 3; ++a) o.position_offset[a] = first[a];
  const SurfaceMesh part = generate::contour(box, o);
  ASSERT_GT(part.num_points(), 50);
  std::set<std::array<float, 3>> all;
  for (Id p = 0; p < whole.num_points(); ++p) all.insert({whole.points[3 * p], whole.points[3 * p + 1], whole.points[3 * p + 2]});
  for (Id p = 0; p < part.num_points(); ++p)
    EXPECT_TRUE(all.count({part.points[3 * p], part.points[3 * p + 1], part.points[3 * p + 2]})) << p;
}

namespace {

// --history in slabs (docs/HISTORY.md): the merged points' keys and
// history_t are the whole volume's; with coarsening it is refused.
TEST(ContourStream, SlabsGiveTheWholeVolumesHistory) {
  ImageGrid g = generate::spherical_distance(24);
  g.origin = {1.5, 2.25, 10.125};
  g.spacing = {0.5, 1.5, 0.3};
  ContourOptions o;
  o.isovalues = {9.5, 4.25};
  o.history = true;
  std::vector<std::uint64_t> whole_keys;
  const SurfaceMesh whole = generate::contour(g, o, nullptr, &whole_keys);
  ASSERT_NE(whole.find_point_field("history_t"), nullptr);
  for (std::size_t planes : {2u, 5u}) {
    GridPlanes src(g);
    std::vector<std::uint64_t> keys;
    const SurfaceMesh m = generate::contour_streamed(src, o, planes * 24 * 24 * sizeof(float), nullptr, nullptr, &keys);
    EXPECT_EQ(keys, whole_keys);
    expect_same(whole, m);
  }
  o.coarsen = true;
  GridPlanes src(g);
  EXPECT_THROW(generate::contour_streamed(src, o, 1 << 20), InputError);
}

}  // namespace

// contour_planes_streamed (a distributed rank's planes under
// --memory-limit): the mesh, global keys and nearest grid points that one
// contour() of those planes read whole gives (ghost planes from outside
// them where the grid has them), at any limit.
TEST(ContourStream, PlanesStreamedEqualOneReadOfThem) {
  const ImageGrid g = generate::spherical_distance(30);
  const std::size_t plane = 30 * 30 * sizeof(float);
  for (auto normals : {generate::ContourNormals::None, generate::ContourNormals::Gradient}) {
    ContourOptions o;
    o.isovalues = {9.5, 13.25};
    o.normals = normals;
    o.curvature = normals == generate::ContourNormals::Gradient;
    const Id ghosts = o.curvature ? 1 : 0;
    for (auto [lo, hi] : {std::array<Id, 2>{0, 12}, {7, 29}, {11, 19}}) {
      const Id below = lo > 0 ? ghosts : 0, above = hi < 29 ? ghosts : 0;
      ImageGrid slab;
      slab.spacing = g.spacing, slab.origin = g.origin;
      slab.allocate({30, 30, hi - lo + 1 + below + above}, g.type);
      std::memcpy(slab.bytes.data(), g.bytes.data() + plane * static_cast<std::size_t>(lo - below),
                  plane * static_cast<std::size_t>(hi - lo + 1 + below + above));
      ContourOptions one = o;
      one.first_plane = lo - below, one.total_planes = 30, one.ghost_below = below, one.ghost_above = above;
      std::vector<std::uint64_t> keys, nearest;
      const SurfaceMesh ref = generate::contour(slab, one, nullptr, &keys, &nearest);
      ASSERT_GT(ref.num_cells(), 0);
      for (std::size_t planes : {4u, 6u, 40u}) {
        SCOPED_TRACE("planes " + std::to_string(lo) + ".." + std::to_string(hi) + " in slabs of " +
                     std::to_string(planes));
        GridPlanes src(g);
        std::vector<std::uint64_t> got_keys, got_nearest;
        generate::StreamStats ss;
        const SurfaceMesh m =
            generate::contour_planes_streamed(src, o, planes * plane, lo, hi, got_keys, &got_nearest, &ss);
        expect_same(ref, m);
        EXPECT_EQ(got_keys, keys);
        EXPECT_EQ(got_nearest, nearest);
        EXPECT_EQ(ss.slabs, src.reads);
      }
    }
  }
}
