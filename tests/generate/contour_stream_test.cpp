#include "keymesh/generate/contour_stream.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "keymesh/core/error.hpp"
#include "keymesh/generate/spherical_distance.hpp"

using namespace keymesh;
using generate::ContourOptions;

namespace {

// Planes served from a grid held in memory (the test's stand-in for a file).
class GridPlanes : public generate::PlaneSource {
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
  EXPECT_THROW(generate::contour_streamed(src, o, 1 << 20), InputError);
}

}  // namespace
