// The CUDA contour's refusals and size arithmetic (src/cuda/contour_limits.hpp),
// host code that runs in every build, with a GPU or without one.
#include "cuda/contour_limits.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>

#include "keymesh/backend/contour.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/cuda/device_contour.hpp"
#include "keymesh/generate/spherical_distance.hpp"

using namespace keymesh;
using generate::ContourOptions;

namespace {

std::string input_error_of(const ContourOptions& o) {
  try {
    cuda::check_gpu_options(o);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Each option the GPU path does not implement is refused by its name, never
// ignored; the defaults pass, and so do coarsening and curvature (the device
// path runs them).
TEST(CudaLimits, UnsupportedOptionsAreRefusedByName) {
  ContourOptions o;
  o.isovalues = {1.5};
  EXPECT_EQ(input_error_of(o), "");
  ContourOptions coarsened = o;
  coarsened.coarsen = true;
  EXPECT_EQ(input_error_of(coarsened), "");
  ContourOptions curved = o;
  curved.curvature = true;
  curved.coarsen = true;
  EXPECT_EQ(input_error_of(curved), "");
  struct Case {
    void (*set)(ContourOptions&);
    const char* name;
  };
  const Case cases[] = {
      {[](ContourOptions& c) { c.history = true; }, "history"},
      {[](ContourOptions& c) { c.output_arrays = [](Id, Id) { return generate::ContourArrays{}; }; }, "output_arrays"},
      {[](ContourOptions& c) { c.total_planes = 40; }, "slab"},
      {[](ContourOptions& c) { c.ghost_below = 1; }, "ghost planes"},
      {[](ContourOptions& c) { c.ghost_above = 1; }, "ghost planes"},
  };
  for (const Case& c : cases) {
    ContourOptions refused = o;
    c.set(refused);
    const std::string m = input_error_of(refused);
    EXPECT_NE(m.find(c.name), std::string::npos) << c.name << ": " << m;
    EXPECT_NE(m.find("--backend cpu"), std::string::npos) << m;
  }
}

// The refusal comes before the device is considered: the same InputError on a
// machine with a GPU, without one, and in a build without CUDA.
TEST(CudaLimits, GhostPlanesWithoutASlabAreRefusedOnTheGpuPath) {
  ContourOptions o;
  o.isovalues = {5.5};
  o.backend = generate::Backend::Cuda;
  o.ghost_above = 1;
  try {
    backend::contour(generate::spherical_distance(16), o);
    FAIL() << "ghost planes on the GPU path must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ghost planes"), std::string::npos) << e.what();
  }
}

TEST(CudaLimits, VoxelsPastCubsIntCountsAreRefused) {
  EXPECT_EQ(cuda::gpu_voxels(2, 2, 2), 1);
  EXPECT_EQ(cuda::gpu_voxels(1291, 1291, 1291), Id{1290} * 1290 * 1290);  // 2,146,689,000 <= 2^31 - 1
  EXPECT_THROW(cuda::gpu_voxels(1292, 1292, 1292), LimitError);           // 2,151,685,171
  EXPECT_THROW(cuda::gpu_voxels(65537, 65537, 2), LimitError);            // 2^32 voxels
}

// The 1040^3 uint8 checkerboard of the review: 4 triangles in each of 1039^3
// voxels, 4,486,489,276 triangles. Summed in 32 bits the count wraps to
// 191,521,980, which would pass the corner limit and size the soup far too
// small; the 64-bit total is refused, naming the real count.
TEST(CudaLimits, TriangleCountsPast2To32AreRefusedNotWrapped) {
  const std::uint64_t triangles = 4ull * 1039 * 1039 * 1039;
  ASSERT_EQ(triangles, 4486489276ull);
  ASSERT_EQ(static_cast<std::uint32_t>(triangles), 191521980u);
  EXPECT_EQ(cuda::gpu_soup_corners(0, static_cast<std::uint32_t>(triangles)), 3 * Id{191521980});
  try {
    cuda::gpu_soup_corners(0, triangles);
    FAIL() << "4,486,489,276 triangles must be refused";
  } catch (const LimitError& e) {
    EXPECT_NE(std::string(e.what()).find("4486489276 triangles"), std::string::npos) << e.what();
  }
  EXPECT_THROW(cuda::gpu_soup_corners(0, std::numeric_limits<std::uint64_t>::max()), LimitError);
}

// The limit is exact: 2^31 - 1 corners at most, counted across isovalues.
TEST(CudaLimits, CornerLimitIsExactAcrossIsovalues) {
  const Id max_corners = std::numeric_limits<int>::max();  // 2,147,483,647
  EXPECT_EQ(cuda::gpu_soup_corners(0, max_corners / 3), 3 * (max_corners / 3));
  EXPECT_THROW(cuda::gpu_soup_corners(0, max_corners / 3 + 1), LimitError);
  EXPECT_EQ(cuda::gpu_soup_corners(30, 10), 60);
  EXPECT_THROW(cuda::gpu_soup_corners(3, max_corners / 3), LimitError);
  EXPECT_EQ(cuda::gpu_soup_corners(max_corners - 1, 0), max_corners - 1);
}

// Device-resident input: what contour_device refuses before any device is
// touched, in every build.
TEST(CudaLimits, DeviceVolumeChecks) {
  static const float samples[8] = {};
  cuda::DeviceVolume v;
  v.grid.dims = {2, 2, 2};
  v.samples = samples;
  ContourOptions o;
  o.isovalues = {0.5};
  EXPECT_NO_THROW(cuda::check_device_volume(v, o));
  auto refused = [](const cuda::DeviceVolume& volume, const ContourOptions& options, const char* what) {
    try {
      cuda::check_device_volume(volume, options);
      ADD_FAILURE() << what << " must be refused";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  cuda::DeviceVolume thin = v;
  thin.grid.dims = {2, 1, 2};
  refused(thin, o, "1 point(s) along axis y");
  cuda::DeviceVolume null = v;
  null.samples = nullptr;
  refused(null, o, "device pointer is null");
  cuda::DeviceVolume wide = v;
  wide.grid.type = ScalarType::Int64;
  refused(wide, o, "int64");
  ContourOptions no_iso = o;
  no_iso.isovalues.clear();
  refused(v, no_iso, "no isovalue");
  ContourOptions curvature = o;  // runs on the GPU (the device path computes it)
  curvature.curvature = true;
  EXPECT_NO_THROW(cuda::check_device_volume(v, curvature));
  // cuda::contour coarsens host samples; device-resident ones are refused.
  ContourOptions coarsen = o;
  coarsen.coarsen = true;
  refused(v, coarsen, "coarsening (--coarsen) of samples in device memory");
  cuda::DeviceVolume huge = v;
  huge.grid.dims = {1292, 1292, 1292};
  EXPECT_THROW(cuda::check_device_volume(huge, o), LimitError);
}

// Host memory handed as "device" samples is refused, never read by a
// kernel: without a GPU (or CUDA) because none is usable, with one because
// cudaPointerGetAttributes says it is not device memory.
TEST(CudaLimits, HostSamplesAreRefusedByContourDevice) {
  const ImageGrid host = generate::spherical_distance(8);
  cuda::DeviceVolume v;
  v.grid.dims = host.dims;
  v.grid.type = host.type;
  v.samples = host.bytes.data();
  ContourOptions o;
  o.isovalues = {3.5};
  EXPECT_THROW(cuda::contour_device(v, o), InputError);
}

}  // namespace
