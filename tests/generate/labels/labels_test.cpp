#include "keymesh/generate/labels/labels.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "keymesh/analyze/topology.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/parallel/threads.hpp"
#include "label_map.hpp"
#include "mesh_measures.hpp"

using namespace keymesh;
using test::enclosed_volume;
using test::label_map;

namespace {

generate::LabelOptions unsmoothed(generate::LabelMethod method = generate::LabelMethod::SurfaceNets) {
  generate::LabelOptions o;
  o.method = method;
  o.smooth_iterations = 0;
  return o;
}

// The mesh contour_labels makes with `threads` worker threads (the count put
// back to every core after).
SurfaceMesh contour_with_threads(const ImageGrid& g, const generate::LabelOptions& o, int threads) {
  parallel::set_thread_count(threads);
  SurfaceMesh mesh = generate::contour_labels(g, o);
  parallel::set_thread_count(0);
  return mesh;
}

}  // namespace

// One voxel: surface nets gives its cube (8 cell centres, 6 quads), closed,
// of volume 1 (sign by orientation); discrete marching cubes the octahedron of its 6 edge
// midpoints (8 triangles; |x| + |y| + |z| <= 1/2 holds 4/3 (1/2)^3 = 1/6).
TEST(Labels, OneVoxelCubeAndOctahedron) {
  const ImageGrid g = label_map({3, 3, 3}, [](Id i, Id j, Id k) { return i == 1 && j == 1 && k == 1 ? 5 : 0; });
  const SurfaceMesh sn = generate::contour_labels(g, unsmoothed());
  EXPECT_EQ(sn.num_points(), 8);
  EXPECT_EQ(sn.num_cells(), 12);
  // Network faces point from the smaller label (0) into the larger (5):
  // inward here, so the signed volume is -1.
  EXPECT_NEAR(enclosed_volume(sn), -1.0, 1e-6);
  const auto t = analyze::check_topology(sn);
  EXPECT_TRUE(t.closed_manifold);
  EXPECT_EQ(t.euler_characteristic, 2);
  const Field* bl = sn.find_cell_field("boundary_labels");
  ASSERT_NE(bl, nullptr);
  ASSERT_EQ(bl->components, 2);
  for (Id c = 0; c < sn.num_cells(); ++c) EXPECT_TRUE(bl->values[2 * c] == 0 && bl->values[2 * c + 1] == 5);

  const SurfaceMesh mc = generate::contour_labels(g, unsmoothed(generate::LabelMethod::DiscreteMarchingCubes));
  EXPECT_EQ(mc.num_points(), 6);
  EXPECT_EQ(mc.num_cells(), 8);
  EXPECT_NEAR(enclosed_volume(mc), 1.0 / 6.0, 1e-6);  // |x| + |y| + |z| <= 1/2
  ASSERT_NE(mc.find_cell_field("label"), nullptr);
}

// Two labels side by side filling the grid: the network has the shared wall
// once (one quad per x-edge between them) and both outer boxes; with padding
// each per-label surface is a closed box of its voxel count.
TEST(Labels, SharedWallOnceAndClosedBoxes) {
  const std::array<Id, 3> n{4, 3, 2};
  const ImageGrid g = label_map(n, [](Id i, Id, Id) { return i < 2 ? 1 : 2; });
  const SurfaceMesh net = generate::contour_labels(g, unsmoothed());
  const Field* bl = net.find_cell_field("boundary_labels");
  Id wall = 0;
  for (Id c = 0; c < net.num_cells(); ++c) wall += bl->values[2 * c] == 1 && bl->values[2 * c + 1] == 2;
  EXPECT_EQ(wall, 2 * n[1] * n[2]);  // x-edges between i = 1 and i = 2: two triangles each
  const auto counts = generate::label_pair_counts(net);
  ASSERT_EQ(counts.size(), 3u);  // (0,1), (0,2), (1,2)
  EXPECT_EQ(counts[2].first, 1);
  EXPECT_EQ(counts[2].faces, wall);
  EXPECT_EQ(counts[2].points, (n[1] + 1) * (n[2] + 1));  // the wall's cells: one plane of (ny+1)(nz+1)

  generate::LabelOptions o = unsmoothed();
  o.per_label = true;
  const SurfaceMesh parts = generate::contour_labels(g, o);
  const auto t = analyze::check_topology(parts);
  EXPECT_TRUE(t.closed_manifold);
  EXPECT_EQ(t.components, 2);
  EXPECT_EQ(t.euler_characteristic, 4);
  EXPECT_NEAR(enclosed_volume(parts), static_cast<double>(n[0] * n[1] * n[2]), 1e-5);
}

TEST(Labels, SmoothingSameBitsAtAnyThreadCount) {
  const ImageGrid g = label_map({9, 8, 7}, [](Id i, Id j, Id k) { return (i * 7 + j * 3 + k * 5) % 11 < 4 ? 1 + (i + k) % 3 : 0; });
  for (auto method : {generate::LabelMethod::SurfaceNets, generate::LabelMethod::DiscreteMarchingCubes}) {
    generate::LabelOptions o;
    o.method = method;
    const SurfaceMesh a = contour_with_threads(g, o, 1);
    const SurfaceMesh b = contour_with_threads(g, o, 2);
    ASSERT_EQ(a.points.size(), b.points.size());
    EXPECT_EQ(std::memcmp(a.points.data(), b.points.data(), 4 * a.points.size()), 0);
    EXPECT_EQ(a.connectivity, b.connectivity);
  }
}

// Per label, one selected label's surface is made in blocks of rows joined
// in row order when threads are spare (labels_surface_nets.cpp), several
// labels' in one block each: the label's surface must be the same bits
// either way, and the first part of the several labels' run.
TEST(Labels, OneLabelInBlocksOfRowsEqualsItsPartOfEveryLabel) {
  // Blobs of three labels touching along edges and corners (ambiguous faces,
  // face points) and a tunnel through label 1.
  const ImageGrid g = label_map({23, 19, 17}, [](Id i, Id j, Id k) -> Id {
    if (i > 3 && i < 18 && j > 3 && j < 15 && k > 2 && k < 14) return (i == 10 && j == 9) ? 0 : 1;
    return (i * 5 + j * 3 + k * 7) % 13 < 5 ? 2 + (i + j + k) % 2 : 0;
  });
  generate::LabelOptions one = unsmoothed();
  one.per_label = true;
  one.labels = {1};
  generate::LabelOptions every = unsmoothed();
  every.per_label = true;
  const SurfaceMesh blocks = contour_with_threads(g, one, 4);
  const SurfaceMesh single = contour_with_threads(g, one, 1);
  const SurfaceMesh all = contour_with_threads(g, every, 3);
  ASSERT_GT(single.num_cells(), 100);
  ASSERT_EQ(blocks.points.size(), single.points.size());
  EXPECT_EQ(std::memcmp(blocks.points.data(), single.points.data(), 4 * single.points.size()), 0);
  EXPECT_EQ(blocks.connectivity, single.connectivity);
  ASSERT_GT(all.connectivity.size(), single.connectivity.size());
  EXPECT_EQ(std::memcmp(all.points.data(), single.points.data(), 4 * single.points.size()), 0);
  EXPECT_TRUE(std::equal(single.connectivity.begin(), single.connectivity.end(), all.connectivity.begin()));
  EXPECT_TRUE(analyze::check_topology(single).closed_manifold);
}

TEST(Labels, RefusesFloatsAndTooManyLabels) {
  ImageGrid f;
  f.allocate({2, 2, 2}, ScalarType::Float32);
  EXPECT_THROW(generate::contour_labels(f, {}), InputError);
  ImageGrid many;
  many.allocate({300, 300, 1}, ScalarType::Int32);
  auto* v = reinterpret_cast<std::int32_t*>(many.data());
  for (Id i = 0; i < many.num_points(); ++i) v[i] = static_cast<std::int32_t>(i);
  try {
    generate::contour_labels(many, {});
    FAIL() << "90000 labels accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("65536"), std::string::npos) << e.what();
  }
}
