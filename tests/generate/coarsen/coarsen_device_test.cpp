// Coarsening's device path (generate/coarsen/coarsen_device.hpp) run on the
// CPU device equals the CPU path bit for bit: coarsen() on any mesh and
// keys, and `contour --coarsen` (both of contour()'s plans) through the
// contour's device path, at 1 and 4 threads.
#include "keymesh/generate/coarsen/coarsen_device.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/device/cpu_device.hpp"
#include "keymesh/generate/labels/labels.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/parallel/threads.hpp"
#include "generate/contour/device_contour_cases.hpp"
#include "generate/labels/label_map.hpp"
#include "same_bits.hpp"

using namespace keymesh;
using generate::ContourNormals;
using generate::ContourOptions;
using generate::ContourWeld;

namespace {

const int kThreadCounts[] = {1, 4};

// coarsen() and the device path on the same mesh and keys: the same bytes
// and the same stats, at every thread count. Returns the CPU's stats.
generate::CoarsenStats expect_device_coarsen_equals_cpu(const SurfaceMesh& mesh, const std::vector<std::uint64_t>& keys,
                                                        std::uint64_t key_range, const std::string& what) {
  generate::CoarsenStats cpu_stats;
  for (int threads : kThreadCounts) {
    parallel::set_thread_count(threads);
    std::ostringstream at;
    at << what << " threads " << threads;
    const SurfaceMesh cpu = generate::coarsen(mesh, keys, key_range, &cpu_stats);
    generate::CoarsenStats st;
    const SurfaceMesh device = generate::coarsen_on_cpu_device(mesh, keys, key_range, &st);
    keymesh::testing::expect_same_bits(device, cpu, at.str());
    EXPECT_EQ(st.points_before, cpu_stats.points_before) << at.str();
    EXPECT_EQ(st.points_after, cpu_stats.points_after) << at.str();
    EXPECT_EQ(st.triangles_before, cpu_stats.triangles_before) << at.str();
    EXPECT_EQ(st.triangles_after, cpu_stats.triangles_after) << at.str();
    EXPECT_EQ(st.folded, cpu_stats.folded) << at.str();
  }
  parallel::set_thread_count(0);
  return cpu_stats;
}

// `contour --coarsen` through the device path (narrow and wide keys)
// against both of contour()'s plans, at every thread count; returns the
// coarse triangles of the last option set.
Id expect_device_contour_coarsen_equals_cpu(const ImageGrid& g, const std::vector<double>& isovalues,
                                            const std::string& what) {
  Id triangles = -1;
  for (ContourOptions opt : keymesh::testing::option_sets(isovalues, true)) {
    for (int threads : kThreadCounts) {
      parallel::set_thread_count(threads);
      const std::string at = keymesh::testing::describe(opt, what + " threads " + std::to_string(threads));
      opt.weld = ContourWeld::KeyReduce;
      generate::ContourStats cpu_stats, st;
      const SurfaceMesh in_pass = generate::contour(g, opt, &cpu_stats);
      opt.weld = ContourWeld::KeyReduceSort;
      const SurfaceMesh sorted = generate::contour(g, opt);
      opt.weld = ContourWeld::KeyReduce;
      const SurfaceMesh device = generate::contour_coarsened_on_cpu_device(g, opt, &st);
      keymesh::testing::expect_same_bits(device, in_pass, at + " (structured plan)");
      keymesh::testing::expect_same_bits(device, sorted, at + " (sort plan)");
      EXPECT_EQ(st.triangles_before_coarsening, cpu_stats.triangles_before_coarsening) << at;
      const SurfaceMesh wide = generate::contour_coarsened_on_cpu_device(g, opt, &st, generate::DeviceKeys::Wide);
      EXPECT_EQ(st.key_bits, 64);
      keymesh::testing::expect_same_bits(wide, in_pass, at + " (64-bit keys)");
      // contour_on_cpu_device takes the same path when asked to coarsen.
      keymesh::testing::expect_same_bits(generate::contour_on_cpu_device(g, opt), in_pass, at + " (contour entry)");
      triangles = in_pass.num_cells();
    }
  }
  parallel::set_thread_count(0);
  return triangles;
}

// The fine contour and its nearest-grid-point keys (what contour() coarsens by).
struct FineContour {
  SurfaceMesh mesh;
  std::vector<std::uint64_t> nearest;
  std::uint64_t key_range = 0;
};

FineContour fine_contour(const ImageGrid& g, const std::vector<double>& isovalues, ContourNormals normals) {
  ContourOptions opt;
  opt.isovalues = isovalues;
  opt.normals = normals;
  FineContour f;
  f.mesh = generate::contour(g, opt, nullptr, nullptr, &f.nearest);
  f.key_range = static_cast<std::uint64_t>(g.num_points()) * isovalues.size();
  return f;
}

template <class T>
ImageGrid integers(std::array<Id, 3> dims, int levels, unsigned seed, ScalarType type) {
  ImageGrid g;
  g.allocate(dims, type);
  T* v = static_cast<T*>(g.data());
  std::mt19937 rng(seed);
  for (Id i = 0; i < g.num_points(); ++i) v[i] = static_cast<T>(rng() % static_cast<unsigned>(levels));
  return g;
}

// Points of a mesh that share their position with another (a split's copies).
Id coincident_points(const SurfaceMesh& m) {
  std::set<std::array<float, 3>> positions;
  for (Id p = 0; p < m.num_points(); ++p) positions.insert({m.points[3 * p], m.points[3 * p + 1], m.points[3 * p + 2]});
  return m.num_points() - static_cast<Id>(positions.size());
}

}  // namespace

TEST(DeviceCoarsen, SphereContourEqualsTheCpuPath) {
  const ImageGrid g = generate::spherical_distance(40);
  for (auto normals : {ContourNormals::None, ContourNormals::Average, ContourNormals::Gradient}) {
    const FineContour f = fine_contour(g, {18.3}, normals);
    const auto st = expect_device_coarsen_equals_cpu(f.mesh, f.nearest, f.key_range, "sphere");
    EXPECT_LT(st.triangles_after, st.triangles_before * 7 / 10);  // it did coarsen
  }
  EXPECT_GT(expect_device_contour_coarsen_equals_cpu(g, {18.3, 9.75}, "sphere"), 1000);
}

TEST(DeviceCoarsen, NoiseEqualsTheCpuPath) {
  const ImageGrid g = keymesh::testing::noise(23, 19, 17, 3);
  const FineContour f = fine_contour(g, {0.0, 0.4}, ContourNormals::Gradient);
  const auto st = expect_device_coarsen_equals_cpu(f.mesh, f.nearest, f.key_range, "noise");
  EXPECT_GT(st.folded, 0);  // noise folds: the rule was exercised
  EXPECT_GT(expect_device_contour_coarsen_equals_cpu(g, {0.0, 0.4}, "noise"), 100);
}

// Integer samples on the isovalue (t = 0 or 1: the crossing sits on a grid
// point; t = 0.5 exactly: nearest the far end), and random levels whose
// sheets pinch: points are split (their copies coincide with them).
TEST(DeviceCoarsen, IntegerSamplesOnTheIsovalueEqualTheCpuPath) {
  const ImageGrid bytes = integers<std::uint8_t>({19, 16, 13}, 5, 7, ScalarType::UInt8);
  EXPECT_GT(expect_device_contour_coarsen_equals_cpu(bytes, {2.0, 1.5}, "uint8"), 100);
  const ImageGrid shorts = integers<std::int16_t>({15, 18, 12}, 3, 9, ScalarType::Int16);
  EXPECT_GT(expect_device_contour_coarsen_equals_cpu(shorts, {1.0}, "int16"), 100);
  const FineContour f = fine_contour(bytes, {2.0, 1.5}, ContourNormals::None);
  expect_device_coarsen_equals_cpu(f.mesh, f.nearest, f.key_range, "uint8 fine");
  EXPECT_GT(coincident_points(generate::coarsen_on_cpu_device(f.mesh, f.nearest, f.key_range)), 0);
}

// A plate one voxel thick with a hole: at isovalue 0.6 both of its sheets
// merge into the grid points of its middle plane (they fold away; where they
// meet at the rim and the hole, non-manifold merges the split undoes); and
// an empty contour.
TEST(DeviceCoarsen, ThinPlatesAndEmptyShapesEqualTheCpuPath) {
  ImageGrid plate;
  plate.allocate({12, 11, 9}, ScalarType::Float32);
  auto* v = static_cast<float*>(plate.data());
  for (Id p = 0; p < plate.num_points(); ++p) {
    const Id i = p % 12, j = p / 12 % 11, k = p / (12 * 11);
    v[p] = k == 4 && !(i == 5 && j == 5) && i > 0 && i < 11 && j > 0 && j < 10 ? 1.f : 0.f;
  }
  EXPECT_GT(expect_device_contour_coarsen_equals_cpu(plate, {0.6, 0.3}, "plate"), 0);
  const FineContour f = fine_contour(plate, {0.6}, ContourNormals::Average);
  const auto st = expect_device_coarsen_equals_cpu(f.mesh, f.nearest, f.key_range, "plate fine");
  EXPECT_GT(st.folded, 0);
  EXPECT_GT(coincident_points(generate::coarsen_on_cpu_device(f.mesh, f.nearest, f.key_range)), 0);

  EXPECT_EQ(expect_device_contour_coarsen_equals_cpu(plate, {7.0}, "no crossing"), 0);
  expect_device_coarsen_equals_cpu(SurfaceMesh{}, {}, 0, "empty mesh");
  SurfaceMesh points_only;  // points, no triangle: every point goes
  points_only.points = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  points_only.point_fields.push_back({"s", 1, {1, 2, 3}});
  EXPECT_EQ(expect_device_coarsen_equals_cpu(points_only, {0, 1, 0}, 2, "points only").points_after, 0);
}

// Keys of any kind, not a contour's: random keys over few groups (many
// collapsed and folded triangles, cell tuples to carry), a key range far
// past the points (the CPU's sort plan) and a tight one (its dense plan).
TEST(DeviceCoarsen, RandomKeysAndCellFieldsEqualTheCpuPath) {
  const FineContour f = fine_contour(generate::spherical_distance(24), {10.2}, ContourNormals::Average);
  SurfaceMesh mesh = f.mesh;
  Field cells{"pair", 2, {}};
  for (Id t = 0; t < mesh.num_cells(); ++t) cells.values.insert(cells.values.end(), {float(t), float(t % 7) - 3.5f});
  mesh.cell_fields.push_back(cells);
  std::mt19937 rng(4);
  for (std::uint64_t groups : {std::uint64_t{50}, std::uint64_t{400}}) {
    std::vector<std::uint64_t> keys(static_cast<std::size_t>(mesh.num_points()));
    for (auto& k : keys) k = rng() % groups;
    const auto st = expect_device_coarsen_equals_cpu(mesh, keys, groups, "random keys");
    EXPECT_GT(st.folded, 0);
    for (auto& k : keys) k = k * 1000003u;  // the same groups, sparse keys
    expect_device_coarsen_equals_cpu(mesh, keys, groups * 1000003u, "sparse keys");
  }
}

// A label surface's boundary_labels (a cell field of label pairs) follow
// their triangles; keys from a lattice of twice the voxel size.
TEST(DeviceCoarsen, LabelSurfaceCellFieldsEqualTheCpuPath) {
  const ImageGrid g = test::label_map({14, 12, 10}, [](Id i, Id j, Id k) {
    return (i - 6) * (i - 6) + (j - 5) * (j - 5) + (k - 4) * (k - 4) < 16 ? (i < 6 ? 1 : 2) : (k > 7 ? 3 : 0);
  });
  generate::LabelOptions lo;
  lo.smooth_iterations = 2;
  const SurfaceMesh labels = generate::contour_labels(g, lo);
  ASSERT_NE(labels.find_cell_field("boundary_labels"), nullptr);
  ASSERT_TRUE(labels.all_triangles());
  std::vector<std::uint64_t> keys(static_cast<std::size_t>(labels.num_points()));
  for (Id p = 0; p < labels.num_points(); ++p) {
    std::uint64_t key = 0;
    for (int a = 2; a >= 0; --a)
      key = key * 16 + static_cast<std::uint64_t>(std::floor((labels.points[3 * p + a] + 1.0) / 2.0));
    keys[static_cast<std::size_t>(p)] = key;
  }
  const auto st = expect_device_coarsen_equals_cpu(labels, keys, 16 * 16 * 16, "labels");
  EXPECT_LT(st.triangles_after, st.triangles_before);
}

TEST(DeviceCoarsen, RefusesWhatTheCpuPathRefuses) {
  SurfaceMesh m;
  m.points = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  m.connectivity = {0, 1, 2};
  EXPECT_THROW(generate::coarsen_on_cpu_device(m, {0, 1}, 4), InputError);  // one key per point
  try {
    generate::coarsen_on_cpu_device(m, {0, 1, 9}, 4);
    ADD_FAILURE() << "a key past the range was not refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("key range"), std::string::npos) << e.what();
  }
  EXPECT_THROW(generate::coarsen(m, {0, 1, 9}, 4), InputError);       // the CPU's dense plan
  EXPECT_THROW(generate::coarsen(m, {0, 1, 9000}, 5000), InputError);  // and its sort plan
  m.offsets = {0, 3};  // a polygon mesh
  EXPECT_THROW(generate::coarsen_on_cpu_device(m, {0, 1, 2}, 4), InputError);
  ContourOptions opt;
  opt.isovalues = {2.5};
  EXPECT_THROW(generate::contour_coarsened_on_cpu_device(generate::spherical_distance(8), opt), InputError);  // coarsen off
  opt.coarsen = true;
  opt.history = true;  // refused as contour() refuses it with --coarsen
  EXPECT_THROW(generate::contour(generate::spherical_distance(8), opt), InputError);
  EXPECT_THROW(generate::contour_coarsened_on_cpu_device(generate::spherical_distance(8), opt), InputError);
}
