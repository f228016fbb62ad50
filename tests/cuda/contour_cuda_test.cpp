// The CUDA backend against the CPU backend: identical meshes, array for
// array and bit for bit. Skipped (with the reason) where keymesh was built
// without CUDA or no device is present, as on CI.
#include <gtest/gtest.h>

#if defined(KEYMESH_HAVE_CUDA)
#include <cuda_runtime.h>
#endif

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "keymesh/backend/contour.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/cuda/device_contour.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "gpu_runs.hpp"

using namespace keymesh;
using generate::Backend;
using generate::ContourNormals;
using generate::ContourOptions;

namespace {

bool same_bits(const Array<float>& a, const Array<float>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

void expect_identical(const ImageGrid& g, ContourOptions o) {
  o.backend = Backend::Cpu;
  const SurfaceMesh cpu = generate::contour(g, o);
  o.backend = Backend::Cuda;
  const SurfaceMesh gpu = backend::contour(g, o);
  EXPECT_TRUE(same_bits(cpu.points, gpu.points));
  EXPECT_EQ(cpu.connectivity, gpu.connectivity);
  ASSERT_EQ(cpu.point_fields.size(), gpu.point_fields.size());
  for (std::size_t i = 0; i < cpu.point_fields.size(); ++i) {
    EXPECT_EQ(cpu.point_fields[i].name, gpu.point_fields[i].name);
    EXPECT_TRUE(same_bits(cpu.point_fields[i].values, gpu.point_fields[i].values)) << cpu.point_fields[i].name;
  }
}

TEST(CudaContour, SphereMatchesTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  for (auto normals : {ContourNormals::None, ContourNormals::Gradient, ContourNormals::Average}) {
    ContourOptions o;
    o.isovalues = {30.5};
    o.normals = normals;
    expect_identical(generate::spherical_distance(64), o);
    o.isovalues = {10.25, 20.001, 31.0};  // several isovalues, one touching samples exactly
    expect_identical(generate::spherical_distance(64), o);
    o.curvature = true;  // mean_curvature from the grid's derivatives, as on the CPU
    expect_identical(generate::spherical_distance(64), o);
  }
}

// Each device plan --weld picks (structured, sort, VERTEX-WELD: generate::
// device_plan_for) against the CPU with the same weld, every normals option.
TEST(CudaContour, EveryPlanMatchesTheCpuBitForBit) {
  SKIP_WITHOUT_GPU();
  std::mt19937 rng(4);
  ImageGrid noise;
  noise.allocate({41, 23, 30}, ScalarType::Int16);
  auto* v = reinterpret_cast<std::int16_t*>(noise.bytes.data());
  for (Id p = 0; p < noise.num_points(); ++p) v[p] = static_cast<std::int16_t>(rng() % 200);
  for (auto weld : {generate::ContourWeld::KeyReduce, generate::ContourWeld::KeyReduceSort,
                    generate::ContourWeld::VertexWeld})
    for (auto normals : {ContourNormals::None, ContourNormals::Gradient, ContourNormals::Average}) {
      ContourOptions o;
      o.weld = weld;
      o.normals = normals;
      o.isovalues = {30.5, 12.0};
      expect_identical(generate::spherical_distance(72), o);
      o.isovalues = {99.5, 100.0};  // samples on the second isovalue
      expect_identical(noise, o);
      o.curvature = true;
      expect_identical(noise, o);
    }
}

// The report's peak device memory: at least the samples (uploaded whole),
// and bounded (the soup, sort buffers and mesh are a few times the output).
TEST(CudaContour, ReportsPeakDeviceMemory) {
  SKIP_WITHOUT_GPU();
  const ImageGrid g = generate::spherical_distance(96);
  ContourOptions o;
  o.isovalues = {40.5};
  o.backend = generate::Backend::Cuda;
  generate::ContourStats st;
  const SurfaceMesh m = backend::contour(g, o, &st);
  EXPECT_GE(st.device_peak_bytes, g.bytes.size());
  EXPECT_LT(st.device_peak_bytes, g.bytes.size() + 200 * static_cast<std::uint64_t>(m.num_cells()) * 12 + (64u << 20));
}

TEST(CudaContour, EveryScalarTypeAndNoise) {
  SKIP_WITHOUT_GPU();
  std::mt19937 rng(9);
  for (ScalarType t : {ScalarType::UInt8, ScalarType::Int16, ScalarType::Float32, ScalarType::Float64}) {
    ImageGrid g;
    g.allocate({33, 20, 17}, t);
    visit_scalars(g, [&](const auto* c) {
      using T = std::remove_cv_t<std::remove_pointer_t<decltype(c)>>;
      T* v = const_cast<T*>(c);
      for (Id p = 0; p < g.num_points(); ++p) v[p] = static_cast<T>(rng() % 200);
    });
    ContourOptions o;
    o.isovalues = {99.5};
    o.normals = ContourNormals::Average;
    expect_identical(g, o);
  }
}

TEST(CudaContour, RefusesWhatItDoesNotDoByName) {
  SKIP_WITHOUT_GPU();
  ContourOptions o;
  o.isovalues = {10.5};
  o.backend = Backend::Cuda;
  o.history = true;
  EXPECT_THROW(backend::contour(generate::spherical_distance(24), o), InputError);
}

TEST(CudaContour, WithoutADeviceTheBackendSaysWhy) {
  std::string why;
  if (cuda::available(&why)) GTEST_SKIP() << "a device is present";
  EXPECT_FALSE(why.empty());
  ContourOptions o;
  o.isovalues = {10.5};
  o.backend = Backend::Cuda;
  try {
    backend::contour(generate::spherical_distance(16), o);
    FAIL() << "--backend cuda without a device must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--backend cuda"), std::string::npos) << e.what();
  }
}

// The backend layer refuses bad input exactly as the CPU contour does, before
// the GPU (or its absence) is considered: the CPU's own message is the reference.
TEST(BackendContour, BadInputIsRefusedAsOnTheCpu) {
  auto message_of = [](const ImageGrid& g, ContourOptions o, Backend where) {
    o.backend = where;
    try {
      if (where == Backend::Cpu) generate::contour(g, o);
      else backend::contour(g, o);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  ImageGrid flat;
  flat.allocate({8, 8, 1}, ScalarType::Float32);  // one plane: no voxel
  ContourOptions o;
  o.isovalues = {0.5};
  EXPECT_NE(message_of(flat, o, Backend::Cpu), "");
  EXPECT_EQ(message_of(flat, o, Backend::Cpu), message_of(flat, o, Backend::Cuda));
  o.isovalues = {};
  const ImageGrid sphere = generate::spherical_distance(8);
  EXPECT_NE(message_of(sphere, o, Backend::Cpu), "");
  EXPECT_EQ(message_of(sphere, o, Backend::Cpu), message_of(sphere, o, Backend::Cuda));
}

// generate is CPU-only: asked for the GPU directly, it refuses by name (the
// choice belongs to backend::contour), and backend::contour on the CPU is
// generate::contour.
TEST(BackendContour, GenerateRunsOnTheCpuAndTheBackendLayerChooses) {
  const ImageGrid g = generate::spherical_distance(20);
  ContourOptions o;
  o.isovalues = {6.5};
  const SurfaceMesh direct = generate::contour(g, o);
  const SurfaceMesh chosen = backend::contour(g, o);
  EXPECT_GT(direct.num_cells(), 0);
  EXPECT_TRUE(same_bits(direct.points, chosen.points));
  EXPECT_EQ(direct.connectivity, chosen.connectivity);
  o.backend = Backend::Cuda;
  EXPECT_THROW(generate::contour(g, o), InputError);
}

#if defined(KEYMESH_HAVE_CUDA)
// A device buffer's floats or ids copied to the host, for the comparison.
template <class T>
std::vector<T> host_copy(const cuda::DeviceBuffer& b, Id n) {
  std::vector<T> out(static_cast<std::size_t>(n));
  if (n) {
    EXPECT_EQ(cudaMemcpy(out.data(), b.get(), out.size() * sizeof(T), cudaMemcpyDeviceToHost), cudaSuccess);
  }
  return out;
}

// Device-resident input (cuda::contour_device): the samples already on the
// GPU, the mesh left there; the same bits as the host path, also mirrored
// back for a C-ordered array's reversed axes.
TEST(CudaContour, DeviceResidentInputGivesTheHostMesh) {
  SKIP_WITHOUT_GPU();
  const ImageGrid g = generate::spherical_distance(48);
  void* samples = nullptr;
  ASSERT_EQ(cudaMalloc(&samples, g.bytes.size()), cudaSuccess);
  ASSERT_EQ(cudaMemcpy(samples, g.bytes.data(), g.bytes.size(), cudaMemcpyHostToDevice), cudaSuccess);
  for (bool mirror : {false, true}) {
    ContourOptions o;
    o.isovalues = {10.25, 20.5};
    o.normals = ContourNormals::Average;
    o.reversed_axes = mirror;
    o.backend = Backend::Cpu;
    SurfaceMesh cpu = generate::contour(g, o);
    if (mirror) {  // what the Python module does to a host mesh of reversed axes
      for (Id p = 0; p < cpu.num_points(); ++p) {
        std::swap(cpu.points[3 * p], cpu.points[3 * p + 2]);
        std::swap(cpu.point_fields[1].values[3 * p], cpu.point_fields[1].values[3 * p + 2]);
      }
      for (Id t = 0; t < cpu.num_cells(); ++t) std::swap(cpu.connectivity[3 * t + 1], cpu.connectivity[3 * t + 2]);
    }
    cuda::DeviceVolume v;
    v.grid.dims = g.dims, v.grid.type = g.type, v.grid.name = g.name;
    v.samples = samples;
    v.ready_after = 1;  // the legacy default stream, as after __dlpack__(stream=1)
    v.mirror_back = mirror;
    o.backend = Backend::Cuda;
    generate::ContourStats st;
    const cuda::DeviceMesh m = cuda::contour_device(v, o, &st);
    ASSERT_EQ(m.points, cpu.num_points());
    ASSERT_EQ(m.triangles, cpu.num_cells());
    const auto xyz = host_copy<float>(m.xyz, 3 * m.points);
    EXPECT_EQ(std::memcmp(xyz.data(), cpu.points.data(), xyz.size() * 4), 0);
    EXPECT_EQ(host_copy<std::uint32_t>(m.connectivity, 3 * m.triangles),
              std::vector<std::uint32_t>(cpu.connectivity.begin(), cpu.connectivity.end()));
    ASSERT_EQ(m.point_fields.size(), 2u);
    for (std::size_t f = 0; f < 2; ++f) {
      const auto values = host_copy<float>(m.point_fields[f].values, m.points * m.point_fields[f].components);
      EXPECT_EQ(std::memcmp(values.data(), cpu.point_fields[f].values.data(), values.size() * 4), 0) << f;
    }
    EXPECT_GT(st.classify, 0.0);  // CUDA events: the device's time, never a host clock's 0
    EXPECT_GT(st.device_peak_bytes, 0u);
  }
  cudaFree(samples);
}
#endif

}  // namespace
