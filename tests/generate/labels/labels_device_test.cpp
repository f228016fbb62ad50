// Label surface nets' device path (src/generate/labels/labels_device.hpp)
// run on the CPU device equals contour_labels(), the CPU path, bit for bit:
// points, triangles, boundary_labels, smoothed (the fold guard included) or
// not, at 1 and several threads, with 32- and 64-bit cell keys.
#include "keymesh/generate/labels/labels_device.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/threads.hpp"
#include "argmax_noise.hpp"
#include "label_map.hpp"
#include "same_bits.hpp"

using namespace keymesh;
using test::label_map;

namespace {

generate::LabelOptions smoothed(int iterations, double relaxation = 0.5) {
  generate::LabelOptions o;
  o.smooth_iterations = iterations;
  o.relaxation = relaxation;
  return o;
}

// The smoothings compared: none, the default (16 iterations, relaxation
// 0.5), a few, and many strong ones (where the fold guard shortens most).
constexpr std::pair<int, double> kSmoothings[] = {{0, 0.5}, {16, 0.5}, {3, 0.5}, {40, 1.0}};

// The device path equals the CPU path, unsmoothed and smoothed as in
// kSmoothings, at 1 and 3 threads and with 64-bit keys, the moves the fold
// guard shortened included; returns the CPU's stats of the default
// smoothing and its mesh unsmoothed.
SurfaceMesh expect_device_equals_cpu(const ImageGrid& g, const std::string& what,
                                     generate::LabelOptions base = generate::LabelOptions{},
                                     generate::LabelStats* default_smoothing = nullptr) {
  SurfaceMesh first;
  for (auto [iterations, relaxation] : kSmoothings) {
    generate::LabelOptions o = base;
    o.smooth_iterations = iterations, o.relaxation = relaxation;
    generate::LabelStats cpu_stats, device_stats;
    const SurfaceMesh cpu = generate::contour_labels(g, o, &cpu_stats);
    std::ostringstream name;
    name << what << " smooth " << iterations << " relaxation " << relaxation;
    for (int threads : {1, 3}) {
      parallel::set_thread_count(threads);
      const SurfaceMesh device = generate::contour_labels_on_cpu_device(g, o, &device_stats, threads == 3);
      keymesh::testing::expect_same_bits(device, cpu, name.str() + (threads == 3 ? " 64-bit keys" : ""));
      EXPECT_EQ(device_stats.soup_corners, cpu_stats.soup_corners) << name.str();
      EXPECT_EQ(device_stats.distinct_labels, cpu_stats.distinct_labels) << name.str();
      EXPECT_EQ(device_stats.surfaces, cpu_stats.surfaces) << name.str();
      EXPECT_EQ(device_stats.guard_shortened, cpu_stats.guard_shortened) << name.str();
    }
    parallel::set_thread_count(0);
    if (iterations == 0) {
      first = cpu;
      EXPECT_EQ(cpu_stats.guard_shortened, 0) << name.str();
    }
    if (iterations == 16 && default_smoothing) *default_smoothing = cpu_stats;
  }
  return first;
}

// White noise of `labels` values (0 the background) on dims n.
ImageGrid noise(std::array<Id, 3> n, int labels, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> u(0, labels - 1);
  return label_map(n, [&](Id, Id, Id) { return u(rng); });
}

// Blobs: each voxel takes the label of its nearest of `labels` random
// seeds (a Voronoi map: large regions, triple lines and corners).
ImageGrid blobs(std::array<Id, 3> n, int labels, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::array<double, 3>> centre(static_cast<std::size_t>(labels));
  for (auto& c : centre)
    for (int a = 0; a < 3; ++a) c[a] = std::uniform_real_distribution<double>(0, double(n[a]))(rng);
  return label_map(n, [&](Id i, Id j, Id k) {
    int best = 0;
    double best_d = 1e300;
    for (int l = 0; l < labels; ++l) {
      const double d = (i - centre[l][0]) * (i - centre[l][0]) + (j - centre[l][1]) * (j - centre[l][1]) +
                       (k - centre[l][2]) * (k - centre[l][2]);
      if (d < best_d) best_d = d, best = l;
    }
    return best;
  });
}

}  // namespace

TEST(DeviceLabels, NoiseOfTwoToFortyLabelsEqualsTheCpuPath) {
  for (int labels : {2, 3, 7, 40}) {
    ImageGrid g = noise({11, 9, 8}, labels, 17u + unsigned(labels));
    g.spacing = {0.5, 1.25, 2.0};
    g.origin = {-3.0, 0.1, 7.0};
    const SurfaceMesh m = expect_device_equals_cpu(g, "noise of " + std::to_string(labels) + " labels");
    EXPECT_GT(m.num_cells(), 500);
  }
}

TEST(DeviceLabels, VoronoiBlobsWithJunctionsEqualTheCpuPath) {
  for (int labels : {4, 25}) {
    const SurfaceMesh m = expect_device_equals_cpu(blobs({24, 20, 17}, labels, 3u), "blobs " + std::to_string(labels));
    EXPECT_GT(m.num_cells(), 2000);
  }
}

// Atlas-like volumes (many labels in blobs, three or more meeting all over):
// where the fold guard acts, so the device path runs it, not only the steps.
TEST(DeviceLabels, AtlasLikeJunctionsWhereTheFoldGuardActsEqualTheCpuPath) {
  const struct {
    int labels, passes;
    std::uint64_t seed;
  } cases[] = {{5, 2, 1}, {12, 2, 2}, {40, 1, 5}};
  for (const auto& c : cases) {
    ImageGrid g = test::argmax_noise({20, 18, 16}, c.labels, c.seed, c.passes);
    g.spacing = {0.9, 1.0, 1.3};
    generate::LabelStats smoothed_stats;
    std::ostringstream what;
    what << "argmax noise of " << c.labels << " labels, " << c.passes << " passes";
    expect_device_equals_cpu(g, what.str(), {}, &smoothed_stats);
    EXPECT_GT(smoothed_stats.guard_shortened, 0) << what.str();
  }
  generate::LabelStats blobs_stats;
  expect_device_equals_cpu(blobs({24, 20, 17}, 25, 4u), "blobs 25, guarded", {}, &blobs_stats);
  EXPECT_GT(blobs_stats.guard_shortened, 0);
}

TEST(DeviceLabels, ThinOneVoxelStructuresEqualTheCpuPath) {
  // A one-voxel line, a one-voxel sheet, a diagonal chain of voxels meeting
  // at edges and corners only, and a lone voxel: the border at every turn.
  const ImageGrid g = label_map({12, 10, 9}, [](Id i, Id j, Id k) {
    if (j == 3 && k == 4) return 1;                   // line along x
    if (i == 8) return 2;                             // sheet across the grid
    if (i == j && j == k && i < 6) return 3;          // corner-to-corner chain
    if (i == 2 && j == 7 && k == 1) return 4;         // lone voxel
    if (i + j == 10 && k == 6 && i < 8) return 5;     // edge-to-edge diagonal
    return 0;
  });
  expect_device_equals_cpu(g, "thin structures");
}

TEST(DeviceLabels, EmptyOneLabelAndTinyVolumesEqualTheCpuPath) {
  const SurfaceMesh empty = expect_device_equals_cpu(label_map({5, 4, 3}, [](Id, Id, Id) { return 0; }), "empty");
  EXPECT_EQ(empty.num_cells(), 0);
  const SurfaceMesh full = expect_device_equals_cpu(label_map({5, 4, 3}, [](Id, Id, Id) { return 9; }), "one label");
  EXPECT_GT(full.num_cells(), 0);  // its box, closed through the padding
  expect_device_equals_cpu(label_map({1, 1, 1}, [](Id, Id, Id) { return 1; }), "one voxel grid");
  expect_device_equals_cpu(label_map({7, 1, 1}, [](Id i, Id, Id) { return int(i % 3); }), "one row");
}

TEST(DeviceLabels, LabelsAtTheBorderSelectionAndBackgroundEqualTheCpuPath) {
  // Labels touching every face of the volume; int16 with negative labels, a
  // background other than 0, and a selection (the rest counts as background).
  ImageGrid g;
  g.allocate({9, 8, 7}, ScalarType::Int16);
  auto* v = static_cast<std::int16_t*>(g.data());
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> u(-3, 4);
  for (Id i = 0; i < g.num_points(); ++i) v[i] = static_cast<std::int16_t>(300 * u(rng));
  expect_device_equals_cpu(g, "int16 every label");
  generate::LabelOptions o;
  o.background = -900;
  o.labels = {0, 1200, -600};
  expect_device_equals_cpu(g, "int16 selection", o);
}

TEST(DeviceLabels, RefusesWhatItLacksByName) {
  const ImageGrid g = label_map({3, 3, 3}, [](Id i, Id, Id) { return int(i); });
  auto message = [&](const generate::LabelOptions& o) {
    try {
      generate::contour_labels_on_cpu_device(g, o);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  generate::LabelOptions o;
  o.per_label = true;
  EXPECT_NE(message(o).find("--per-label"), std::string::npos);
  o = {};
  o.method = generate::LabelMethod::DiscreteMarchingCubes;
  EXPECT_NE(message(o).find("discrete-mc"), std::string::npos);
  o = {};
  o.coarsen = true;
  EXPECT_NE(message(o).find("--coarsen"), std::string::npos);
  o = {};
  o.smooth_iterations = 16;  // smoothing runs, its fold guard too
  EXPECT_EQ(message(o), "no error");
  // And what the CPU path refuses: a float volume, a bad relaxation.
  ImageGrid f;
  f.allocate({2, 2, 2}, ScalarType::Float32);
  EXPECT_THROW(generate::contour_labels_on_cpu_device(f, {}), InputError);
  EXPECT_THROW(generate::contour_labels_on_cpu_device(g, smoothed(3, 0.0)), InputError);
}
