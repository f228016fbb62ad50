// `contour --coarsen`, the dual and label surface nets on the GPU
// (keymesh/cuda/backend.hpp, keymesh/cuda/surfaces.hpp, reached through the
// backend layer as the CLI reaches them) against their CPU paths, every array
// bit for bit, each GPU run twice (the second equal to the first:
// deterministic). Skipped, saying why, where keymesh was built without CUDA
// or no device is present; the refusals (bad input as on the CPU, what the
// GPU lacks by name, no device naming --backend cpu) run everywhere.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <utility>

#include "generate/labels/argmax_noise.hpp"
#include "generate/labels/label_map.hpp"
#include "keymesh/backend/contour.hpp"
#include "keymesh/backend/dual.hpp"
#include "keymesh/backend/labels.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "gpu_runs.hpp"
#include "same_bits.hpp"

using namespace keymesh;
using generate::Backend;
using generate::ContourNormals;
using generate::ContourOptions;
using generate::LabelOptions;
using keymesh::testing::expect_gpu_twice;
using keymesh::testing::expect_same_bits;
using keymesh::testing::refusal;

namespace {

ImageGrid noise(Id n, unsigned seed) {
  ImageGrid g;
  g.allocate({n, n + 1, n - 1}, ScalarType::Float32);
  float* v = static_cast<float*>(g.data());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (Id i = 0; i < g.num_points(); ++i) v[i] = u(rng);
  return g;
}

// Integer samples, many of them on the isovalue (the contour's ties).
ImageGrid integers(Id n) {
  ImageGrid g;
  g.allocate({n, n, n}, ScalarType::Int16);
  auto* v = static_cast<std::int16_t*>(g.data());
  for (Id i = 0; i < g.num_points(); ++i) v[i] = static_cast<std::int16_t>((i * 7919) % 11);
  return g;
}

void expect_coarsened(const ImageGrid& g, std::vector<double> isovalues, const std::string& what) {
  for (auto normals : {ContourNormals::None, ContourNormals::Gradient, ContourNormals::Average}) {
    ContourOptions o;
    o.isovalues = isovalues;
    o.normals = normals;
    o.coarsen = true;
    o.scalars = normals == ContourNormals::Gradient;
    expect_gpu_twice(
        [&](Backend b) {
          o.backend = b;
          return backend::contour(g, o);
        },
        what + " normals " + std::to_string(int(normals)));
  }
}

SurfaceMesh sphere_surface(Id n, double iso) {
  ContourOptions o;
  o.isovalues = {iso};
  o.normals = ContourNormals::Average;
  return generate::contour(generate::spherical_distance(n), o);
}

LabelOptions unsmoothed() {
  LabelOptions o;
  o.smooth_iterations = 0;  // the network alone (smoothing has its own tests)
  return o;
}

ImageGrid label_noise(std::array<Id, 3> n, int labels, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> u(0, labels - 1);
  return test::label_map(n, [&](Id, Id, Id) { return u(rng); });
}

}  // namespace

TEST(CudaCoarsen, SphereNoiseAndIntegersMatchTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  expect_coarsened(generate::spherical_distance(40), {12.5, 7.001}, "sphere 40");
  expect_coarsened(noise(33, 5), {0.0, 0.4}, "noise 33");
  expect_coarsened(integers(21), {5.0}, "integers on the isovalue");
  expect_coarsened(generate::spherical_distance(12), {100.0}, "empty");
}

TEST(CudaCoarsen, LargeGridMatchesTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  expect_coarsened(generate::spherical_distance(256), {100.5}, "sphere 256");
}

TEST(CudaDual, ClosedOpenAndDualOfDualMatchTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  const SurfaceMesh closed = sphere_surface(40, 15.5);
  expect_gpu_twice([&](Backend b) { return backend::dual(closed, b); }, "closed sphere");
  const SurfaceMesh dual = generate::dual(closed);
  expect_gpu_twice([&](Backend b) { return backend::dual(dual, b); }, "dual of the dual");
  // The sphere cut by the grid's faces: open fans at the border.
  const SurfaceMesh open = sphere_surface(24, 13.5);
  expect_gpu_twice([&](Backend b) { return backend::dual(open, b); }, "open sphere");
  expect_gpu_twice([&](Backend b) { return backend::dual(SurfaceMesh{}, b); }, "empty");
}

TEST(CudaDual, StatisticsMatchTheCpu) {
  SKIP_WITHOUT_GPU();
  const SurfaceMesh open = sphere_surface(24, 13.5);
  generate::DualStats cpu, gpu;
  backend::dual(open, Backend::Cpu, &cpu);
  backend::dual(open, Backend::Cuda, &gpu);
  EXPECT_EQ(gpu.boundary_fans, cpu.boundary_fans);
  EXPECT_EQ(gpu.nonmanifold_points, cpu.nonmanifold_points);
  EXPECT_EQ(gpu.skipped_fans, cpu.skipped_fans);
  EXPECT_GT(cpu.boundary_fans, 0);
}

TEST(CudaLabels, NoiseBlobsAndSelectionsMatchTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  LabelOptions o = unsmoothed();
  auto labels = [&](const ImageGrid& g, const std::string& what) {
    expect_gpu_twice([&](Backend b) { return backend::contour_labels(g, o, b); }, what);
  };
  labels(label_noise({17, 13, 11}, 2, 1), "noise of 2 labels");
  labels(label_noise({31, 29, 23}, 40, 2), "noise of 40 labels");
  labels(test::label_map({40, 36, 30}, [](Id i, Id j, Id k) { return int((i / 7 + j / 5 + k / 6) % 5); }), "blocks");
  labels(test::label_map({5, 4, 3}, [](Id, Id, Id) { return 0; }), "empty");
  o.labels = {1, 3};
  o.background = 2;
  labels(label_noise({19, 17, 15}, 6, 3), "selection and background");
}

// Smoothed, the fold guard included: atlas-like volumes (many labels in
// blobs, three or more meeting all over), where the guard shortens moves,
// at the default smoothing, a few iterations and many strong ones.
TEST(CudaLabels, SmoothedWithTheFoldGuardMatchesTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  const ImageGrid atlas = test::argmax_noise({40, 36, 32}, 12, 2, 2);
  const ImageGrid noise40 = label_noise({31, 29, 23}, 40, 2);
  for (auto [iterations, relaxation] : {std::pair{16, 0.5}, std::pair{3, 0.5}, std::pair{40, 1.0}}) {
    LabelOptions o;
    o.smooth_iterations = iterations;
    o.relaxation = relaxation;
    const std::string what = " smooth " + std::to_string(iterations);
    generate::LabelStats cpu, gpu;
    expect_gpu_twice([&](Backend b) { return backend::contour_labels(atlas, o, b, b == Backend::Cpu ? &cpu : &gpu); },
                     "argmax noise of 12 labels" + what);
    EXPECT_GT(cpu.guard_shortened, 0);
    EXPECT_EQ(gpu.guard_shortened, cpu.guard_shortened);
    expect_gpu_twice([&](Backend b) { return backend::contour_labels(noise40, o, b); }, "noise of 40 labels" + what);
  }
  const ImageGrid empty = test::label_map({5, 4, 3}, [](Id, Id, Id) { return 0; });
  expect_gpu_twice([&](Backend b) { return backend::contour_labels(empty, LabelOptions{}, b); }, "empty, smoothed");
}

TEST(CudaLabels, LargeVolumeMatchesTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  const ImageGrid g = test::label_map({200, 190, 180}, [](Id i, Id j, Id k) {
    const Id d = (i - 100) * (i - 100) + (j - 95) * (j - 95) + (k - 90) * (k - 90);
    return int(d / 900 % 7);
  });
  expect_gpu_twice([&](Backend b) { return backend::contour_labels(g, unsmoothed(), b); }, "shells 200");
  expect_gpu_twice([&](Backend b) { return backend::contour_labels(g, LabelOptions{}, b); }, "shells 200, smooth 16");
}

// Bad input is refused by the GPU path with the CPU's own message, before
// the GPU (or its absence) is considered.
TEST(BackendSurfaces, BadInputIsRefusedAsOnTheCpu) {
  SurfaceMesh bad_ids;
  bad_ids.points = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  bad_ids.connectivity = {0, 1, 7};
  ImageGrid floats;
  floats.allocate({4, 4, 4}, ScalarType::Float32);
  const ImageGrid labels = label_noise({4, 4, 4}, 3, 4);
  LabelOptions bad_relaxation = unsmoothed();
  bad_relaxation.relaxation = 1.5;
  ContourOptions no_isovalue;
  no_isovalue.coarsen = true;
  const std::function<void(Backend)> cases[] = {
      [&](Backend b) { backend::dual(bad_ids, b); },
      [&](Backend b) { backend::contour_labels(floats, unsmoothed(), b); },
      [&](Backend b) { backend::contour_labels(labels, bad_relaxation, b); },
      [&](Backend b) {
        no_isovalue.backend = b;
        backend::contour(generate::spherical_distance(8), no_isovalue);
      },
  };
  for (const auto& run : cases) {
    const std::string cpu = refusal([&] { run(Backend::Cpu); });
    EXPECT_NE(cpu, "");
    EXPECT_EQ(refusal([&] { run(Backend::Cuda); }), cpu);
  }
}

// What the label path lacks is refused by name, naming --backend cpu, on any
// machine (before the device is considered).
TEST(BackendSurfaces, WhatTheLabelPathLacksIsRefusedByName) {
  const ImageGrid g = label_noise({6, 5, 4}, 3, 6);
  const std::pair<std::string, std::function<void(LabelOptions&)>> cases[] = {
      {"discrete-mc", [](LabelOptions& o) { o.method = generate::LabelMethod::DiscreteMarchingCubes; }},
      {"--per-label", [](LabelOptions& o) { o.per_label = true; }},
      {"--coarsen", [](LabelOptions& o) { o.coarsen = true; }},
  };
  for (const auto& [name, set] : cases) {
    LabelOptions o = unsmoothed();
    set(o);
    const std::string why = refusal([&] { backend::contour_labels(g, o, Backend::Cuda); });
    EXPECT_NE(why.find(name), std::string::npos) << why;
    EXPECT_NE(why.find("(use --backend cpu)"), std::string::npos) << why;
  }
}

// Without a usable device each new GPU path says why in one line naming
// --backend cpu (InputError), as the contour does.
TEST(BackendSurfaces, WithoutADeviceEachGeneratorSaysWhyAndNamesTheCpu) {
  std::string why;
  if (cuda::available(&why)) GTEST_SKIP() << "a device is present";
  ContourOptions coarsen;
  coarsen.isovalues = {2.5};
  coarsen.coarsen = true;
  coarsen.backend = Backend::Cuda;
  const std::function<void()> cases[] = {
      [&] { backend::contour(generate::spherical_distance(8), coarsen); },
      [&] { backend::dual(sphere_surface(8, 2.5), Backend::Cuda); },
      [&] { backend::contour_labels(label_noise({5, 5, 5}, 3, 7), unsmoothed(), Backend::Cuda); },
  };
  for (const auto& run : cases) {
    const std::string message = refusal(run);
    EXPECT_EQ(message.rfind("--backend cuda: ", 0), 0u) << message;
    EXPECT_NE(message.find(why), std::string::npos) << message;
    EXPECT_NE(message.find("(use --backend cpu)"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}
