// The unstructured generators on the GPU (keymesh/cuda/unstructured.hpp,
// reached through the backend layer as the CLI reaches them) against their
// CPU paths: marching tetrahedra, subdivision (triangles 1 -> 4 linear and
// Bezier, tets 1 -> 8), the 5- and 24-tet tetrahedralizations. Every array
// bit for bit, on small and large inputs, each GPU run twice (the second
// equal to the first: deterministic). Skipped, saying why, where keymesh was
// built without CUDA or no device is present; the refusals (bad input as on
// the CPU, what the GPU lacks by name, no device naming --backend cpu) run
// everywhere.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>

#include "keymesh/backend/contour.hpp"
#include "keymesh/backend/subdivide.hpp"
#include "keymesh/backend/tetrahedralize.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/generate/unstructured/contour_tets.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "gpu_runs.hpp"
#include "same_bits.hpp"
#include "generate/unstructured/tet_grid_cases.hpp"

using namespace keymesh;
using keymesh::testing::tet_noise;
using keymesh::testing::tets_of;
using generate::Backend;
using generate::ContourNormals;
using generate::ContourOptions;
using generate::SubdivideOptions;
using generate::SubdivideScheme;
using keymesh::testing::expect_gpu_twice;
using keymesh::testing::expect_same_bits;
using keymesh::testing::refusal;

namespace {

void expect_tets_contour(const UnstructuredGrid& g, const std::vector<double>& isovalues, const std::string& what) {
  for (auto normals : {ContourNormals::None, ContourNormals::Average}) {
    ContourOptions o;
    o.isovalues = isovalues;
    o.normals = normals;
    expect_gpu_twice(
        [&](Backend b) {
          o.backend = b;
          return backend::contour(g, o);
        },
        what + " normals " + std::to_string(int(normals)));
  }
}

SurfaceMesh sphere_surface(Id n) {
  ContourOptions o;
  o.isovalues = {double(n) / 2 - 1 + 0.001};
  o.normals = ContourNormals::Average;
  return generate::contour(generate::spherical_distance(n), o);
}

void expect_subdivided(const SurfaceMesh& m, SubdivideScheme scheme, int levels, const std::string& what) {
  SubdivideOptions o;
  o.levels = levels;
  o.scheme = scheme;
  expect_gpu_twice([&](Backend b) { return backend::subdivide(m, o, b); },
                                what + " scheme " + std::to_string(int(scheme)) + " levels " + std::to_string(levels));
}

void expect_tetrahedralized(const ImageGrid& g, int scheme, const std::string& what) {
  expect_gpu_twice([&](Backend b) { return backend::tetrahedralize(g, scheme, false, b); },
                                     what + " scheme " + std::to_string(scheme));
}

}  // namespace

TEST(CudaTets, SphereNoiseAndNaNMatchTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  expect_tets_contour(tets_of(generate::spherical_distance(18)), {7.3}, "sphere 18");
  expect_tets_contour(tets_of(tet_noise(11, 4)), {0.0, 0.25}, "noise");
  ImageGrid ints;
  ints.allocate({9, 10, 11}, ScalarType::Float32);
  float* v = static_cast<float*>(ints.data());
  std::mt19937 rng(8);
  for (Id i = 0; i < ints.num_points(); ++i) v[i] = float(rng() % 5);  // many samples exactly on 2
  expect_tets_contour(tets_of(ints), {2.0}, "integers on the isovalue");
  for (Id i = 0; i < ints.num_points(); i += 6)
    v[i] = i % 12 ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
  expect_tets_contour(tets_of(ints), {1.5}, "NaN and inf");
  expect_tets_contour(tets_of(generate::spherical_distance(6)), {50.0}, "empty");
}

TEST(CudaTets, LargeGridMatchesTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  const UnstructuredGrid g = tets_of(generate::spherical_distance(96));  // 4.3 M tets, 64-bit keys
  expect_tets_contour(g, {20.5, 47.001}, "sphere 96");
}

TEST(CudaSubdivide, TrianglesMatchTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  const SurfaceMesh small = sphere_surface(20);
  for (auto scheme : {SubdivideScheme::Linear, SubdivideScheme::Bezier})
    for (int levels : {0, 1, 3}) expect_subdivided(small, scheme, levels, "sphere 20");
  const SurfaceMesh large = sphere_surface(128);  // 150 k triangles -> 2.4 M and 9.6 M
  expect_subdivided(large, SubdivideScheme::Bezier, 2, "sphere 128");
  expect_subdivided(large, SubdivideScheme::Linear, 3, "sphere 128");
}

TEST(CudaSubdivide, TetsMatchTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  SubdivideOptions o;
  for (Id n : {Id{7}, Id{40}})  // 1,080 and 296,595 tets; 40: 19 M after two levels
    for (int levels : {1, 2}) {
      o.levels = levels;
      const UnstructuredGrid g = tets_of(generate::spherical_distance(n));
      expect_gpu_twice([&](Backend b) { return backend::subdivide(g, o, b); },
                                         "tets of sphere " + std::to_string(n) + " levels " + std::to_string(levels));
    }
}

TEST(CudaTetrahedralize, GridsMatchTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  ImageGrid sphere = generate::spherical_distance(13);
  sphere.origin = {1.5, -2, 0.25};
  sphere.spacing = {0.5, -1.5, 2};  // mirrored: two corners of every tet swapped
  ImageGrid thin;
  thin.allocate({2, 7, 5}, ScalarType::Int16);
  auto* v = static_cast<std::int16_t*>(thin.data());
  for (Id i = 0; i < thin.num_points(); ++i) v[i] = static_cast<std::int16_t>(i * 37 - 900);
  for (int scheme : {5, 24}) {
    expect_tetrahedralized(sphere, scheme, "mirrored sphere 13");
    expect_tetrahedralized(thin, scheme, "thin int16");
  }
  expect_tetrahedralized(generate::spherical_distance(160), 5, "sphere 160");  // 20 M tets
  expect_tetrahedralized(generate::spherical_distance(96), 24, "sphere 96");   // 20 M tets
}

// Bad input is refused by the GPU path with the CPU's own message, before
// the GPU (or its absence) is considered.
TEST(BackendUnstructured, BadInputIsRefusedAsOnTheCpu) {
  UnstructuredGrid no_field = generate::tetrahedralize5(generate::spherical_distance(5));
  no_field.point_fields.clear();
  ContourOptions o;
  o.isovalues = {1.5};
  const SurfaceMesh polygons = [] {
    SurfaceMesh m = sphere_surface(8);
    m.point_fields.clear();  // Bezier needs the normals
    return m;
  }();
  SubdivideOptions bezier;
  bezier.scheme = SubdivideScheme::Bezier;
  ImageGrid flat;
  flat.allocate({4, 1, 4}, ScalarType::Float32);
  const std::function<void(Backend)> cases[] = {
      [&](Backend b) {
        o.backend = b;
        backend::contour(no_field, o);
      },
      [&](Backend b) { backend::subdivide(polygons, bezier, b); },
      [&](Backend b) { backend::tetrahedralize(flat, 5, false, b); },
      [&](Backend b) { backend::tetrahedralize(flat, 24, false, b); },
  };
  for (const auto& run : cases) {
    const std::string cpu = refusal([&] { run(Backend::Cpu); });
    EXPECT_NE(cpu, "");
    EXPECT_EQ(refusal([&] { run(Backend::Cuda); }), cpu);
  }
}

// What the GPU paths lack is refused by name, naming --backend cpu, on any
// machine (before the device is considered).
TEST(BackendUnstructured, WhatTheGpuLacksIsRefusedByName) {
  const UnstructuredGrid tets = tets_of(generate::spherical_distance(6));
  ContourOptions o;
  o.isovalues = {2.5};
  o.backend = Backend::Cuda;
  o.weld = generate::ContourWeld::VertexWeld;
  SubdivideOptions vertexweld;
  vertexweld.weld = generate::SubdivideWeld::VertexWeld;
  const UnstructuredGrid hexes = [] {
    UnstructuredGrid h;
    h.uniform_type = CellType::Hexahedron;
    return h;
  }();
  const std::pair<std::string, std::function<void()>> cases[] = {
      {"VERTEX-WELD", [&] { backend::contour(tets, o); }},
      {"VERTEX-WELD", [&] { backend::subdivide(tets, vertexweld, Backend::Cuda); }},
      {"VERTEX-WELD", [&] { backend::tetrahedralize(generate::spherical_distance(6), 24, true, Backend::Cuda); }},
      {"hexahedra", [&] { backend::tetrahedralize(hexes, 5, false, Backend::Cuda); }},
  };
  for (const auto& [name, run] : cases) {
    const std::string why = refusal(run);
    EXPECT_NE(why.find(name), std::string::npos) << why;
    EXPECT_NE(why.find("--backend cpu"), std::string::npos) << why;
  }
  o.weld = generate::ContourWeld::KeyReduce;
  o.coarsen = true;
  EXPECT_NE(refusal([&] { backend::contour(tets, o); }).find("coarsening"), std::string::npos);
}

// Without a usable device every new GPU path says why in one line naming
// --backend cpu (InputError), as the contour does.
TEST(BackendUnstructured, WithoutADeviceEveryGeneratorSaysWhyAndNamesTheCpu) {
  std::string why;
  if (cuda::available(&why)) GTEST_SKIP() << "a device is present";
  const ImageGrid grid = generate::spherical_distance(8);
  const UnstructuredGrid tets = tets_of(grid);
  ContourOptions o;
  o.isovalues = {2.5};
  o.backend = Backend::Cuda;
  const std::function<void()> cases[] = {
      [&] { backend::contour(grid, o); },
      [&] { backend::contour(tets, o); },
      [&] { backend::subdivide(sphere_surface(8), SubdivideOptions{}, Backend::Cuda); },
      [&] { backend::subdivide(tets, SubdivideOptions{}, Backend::Cuda); },
      [&] { backend::tetrahedralize(grid, 5, false, Backend::Cuda); },
      [&] { backend::tetrahedralize(grid, 24, false, Backend::Cuda); },
  };
  for (const auto& run : cases) {
    const std::string message = refusal(run);
    EXPECT_EQ(message.rfind("--backend cuda: ", 0), 0u) << message;
    EXPECT_NE(message.find(why), std::string::npos) << message;
    EXPECT_NE(message.find("(use --backend cpu)"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}
