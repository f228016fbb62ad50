#include "mesh_measures.hpp"
#include "keymesh/generate/contour/contour.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "keymesh/generate/contour/marching_cubes_table.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/parallel/threads.hpp"
#include "uniform_noise.hpp"

using namespace keymesh;
using generate::ContourNormals;
using generate::ContourOptions;
using generate::ContourWeld;

namespace {

// Independent reference for the point count: grid edges whose end samples
// straddle the isovalue (inside means value >= iso), counted by brute force.
Id straddling_edges(const ImageGrid& g, double iso) {
  const float* v = static_cast<const float*>(g.data());
  const Id nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  Id count = 0;
  for (Id k = 0; k < nz; ++k)
    for (Id j = 0; j < ny; ++j)
      for (Id i = 0; i < nx; ++i) {
        const Id id = i + nx * (j + ny * k);
        const bool in = v[id] >= iso;
        if (i + 1 < nx && in != (v[id + 1] >= iso)) ++count;
        if (j + 1 < ny && in != (v[id + nx] >= iso)) ++count;
        if (k + 1 < nz && in != (v[id + nx * ny] >= iso)) ++count;
      }
  return count;
}

// Edges of a triangle mesh with the number of triangles using each.
std::map<std::pair<PointIndex, PointIndex>, int> edge_use(const SurfaceMesh& m) {
  std::map<std::pair<PointIndex, PointIndex>, int> use;
  for (Id t = 0; t < m.num_cells(); ++t)
    for (int e = 0; e < 3; ++e) {
      PointIndex a = m.connectivity[3 * t + e], b = m.connectivity[3 * t + (e + 1) % 3];
      ++use[{std::min(a, b), std::max(a, b)}];
    }
  return use;
}

}  // namespace

TEST(MarchingCubesTable, ComplementaryCasesAndCounts) {
  const auto& t = generate::marching_cubes_table();
  EXPECT_EQ(t.triangle_count[0], 0);
  EXPECT_EQ(t.triangle_count[255], 0);
  for (int c = 0; c < 8; ++c) EXPECT_EQ(t.triangle_count[1 << c], 1) << "single corner " << c;
  // Every case: the triangles' edges are exactly the cut edges of the case.
  for (int cs = 0; cs < 256; ++cs) {
    std::set<int> cut, used;
    for (int e = 0; e < 12; ++e)
      if (((cs >> t.edges[e].corner0) & 1) != ((cs >> t.edges[e].corner1) & 1)) cut.insert(e);
    for (int i = 0; i < 3 * t.triangle_count[cs]; ++i) used.insert(t.triangle_edges[cs][i]);
    EXPECT_EQ(cut, used) << "case " << cs;
  }
}

TEST(Contour, PointCountEqualsStraddlingEdges) {
  for (Id n : {9, 16, 33}) {
    const ImageGrid g = generate::spherical_distance(n);
    for (double iso : {2.3, double(n) / 2 - 1.5, double(n) / 2 - 1 + 0.001}) {
      ContourOptions opt;
      opt.isovalues = {iso};
      const SurfaceMesh m = generate::contour(g, opt);
      EXPECT_EQ(m.num_points(), straddling_edges(g, iso)) << n << " " << iso;
    }
  }
}

TEST(Contour, ClosedSphereIsClosedManifoldWithEulerTwo) {
  const Id n = 40;
  const ImageGrid g = generate::spherical_distance(n);
  ContourOptions opt;
  opt.isovalues = {double(n) / 2 - 1.5};
  const SurfaceMesh m = generate::contour(g, opt);
  const auto use = edge_use(m);
  for (const auto& [e, count] : use) ASSERT_EQ(count, 2) << "edge " << e.first << "-" << e.second;
  const Id chi = m.num_points() - static_cast<Id>(use.size()) + m.num_cells();
  EXPECT_EQ(chi, 2);
  // No two points at the same position.
  auto p = test::sorted_points(m);
  EXPECT_EQ(std::adjacent_find(p.begin(), p.end()), p.end());
}

TEST(Contour, TrianglesFaceOutwardOnSphere) {
  const Id n = 24;
  const ImageGrid g = generate::spherical_distance(n);
  ContourOptions opt;
  opt.isovalues = {7.5};
  // Inside is value >= iso: the far region. Lower values (the centre) are
  // outside, so normals must point towards the centre.
  const SurfaceMesh m = generate::contour(g, opt);
  const double c = n / 2;
  for (Id t = 0; t < m.num_cells(); ++t) {
    const float* a = &m.points[3 * m.connectivity[3 * t]];
    const float* b = &m.points[3 * m.connectivity[3 * t + 1]];
    const float* d = &m.points[3 * m.connectivity[3 * t + 2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    const double nrm[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double r[3] = {a[0] - c, a[1] - c, a[2] - c};
    ASSERT_LT(nrm[0] * r[0] + nrm[1] * r[1] + nrm[2] * r[2], 0) << "triangle " << t;
  }
}

namespace {
// The n^3 spherical distance field's contour at `iso` (centre n / 2).
SurfaceMesh sphere_contour(Id n, double iso, ContourNormals normals) {
  ContourOptions opt;
  opt.isovalues = {iso};
  opt.normals = normals;
  return generate::contour(generate::spherical_distance(n), opt);
}
}  // namespace

TEST(Contour, PointsLieOnTheSphereAndScalarsEqualIso) {
  const SurfaceMesh m = sphere_contour(48, 17.25, ContourNormals::Gradient);
  const Field* s = m.find_point_field("distance");
  const Field* nr = m.find_point_field("Normals");
  ASSERT_TRUE(s && nr);
  for (Id p = 0; p < m.num_points(); ++p) {
    const double r = std::hypot(m.points[3 * p] - 24.0, m.points[3 * p + 1] - 24.0, m.points[3 * p + 2] - 24.0);
    // Linear interpolation of a distance field along a grid edge: error is
    // at most the sagitta over one voxel, < 1/(2r) voxels.
    ASSERT_NEAR(r, 17.25, 0.5 / 17.25 + 1e-4);
    ASSERT_NEAR(s->values[p], 17.25, 1e-4);
    // Outward normal points to lower values: towards the centre.
    const double dot = (nr->values[3 * p] * (m.points[3 * p] - 24.0) + nr->values[3 * p + 1] * (m.points[3 * p + 1] - 24.0) +
                        nr->values[3 * p + 2] * (m.points[3 * p + 2] - 24.0)) / r;
    ASSERT_LT(dot, -0.95);
  }
}

TEST(Contour, AveragedNormalsAreUnitAndPointInward) {
  const SurfaceMesh m = sphere_contour(40, 15.3, ContourNormals::Average);
  const Field* nr = m.find_point_field("Normals");
  ASSERT_TRUE(nr);
  for (Id p = 0; p < m.num_points(); ++p) {
    const float* v = &nr->values[3 * p];
    ASSERT_NEAR(std::hypot(v[0], v[1], v[2]), 1.0, 1e-5);
    const double r[3] = {m.points[3 * p] - 20.0, m.points[3 * p + 1] - 20.0, m.points[3 * p + 2] - 20.0};
    const double len = std::hypot(r[0], r[1], r[2]);
    ASSERT_LT((v[0] * r[0] + v[1] * r[1] + v[2] * r[2]) / len, -0.9);
  }
}

TEST(Contour, VertexWeldGivesTheSameMeshUpToRenumbering) {
  const ImageGrid g = generate::spherical_distance(30);
  for (auto normals : {ContourNormals::None, ContourNormals::Gradient, ContourNormals::Average}) {
    ContourOptions a;
    a.isovalues = {11.7, 6.2};
    a.normals = normals;
    ContourOptions b = a;
    b.weld = ContourWeld::VertexWeld;
    const SurfaceMesh ma = generate::contour(g, a), mb = generate::contour(g, b);
    ASSERT_EQ(ma.num_points(), mb.num_points());
    ASSERT_EQ(ma.num_cells(), mb.num_cells());
    EXPECT_EQ(test::sorted_points(ma), test::sorted_points(mb));
    EXPECT_EQ(test::triangle_set(ma), test::triangle_set(mb));
  }
}

TEST(Contour, BothKeyReducePlansGiveTheIdenticalMesh) {
  // The dense plan (direct addressing) and the sort plan both number groups
  // by increasing key: the meshes must be equal array for array, not only up
  // to renumbering. Odd sizes put keys at 64-bit word borders.
  for (Id n : {65, 66, 128}) {
    const ImageGrid g = generate::spherical_distance(n);
    for (auto normals : {ContourNormals::None, ContourNormals::Average}) {
      ContourOptions opt;
      opt.isovalues = {double(n) / 2 - 1.2, 9.9, double(n) / 2 - 1 + 0.001};
      opt.normals = normals;
      const SurfaceMesh ref = generate::contour(g, opt);
      opt.weld = ContourWeld::KeyReduceSort;
      const SurfaceMesh m = generate::contour(g, opt);
      EXPECT_EQ(m.points, ref.points) << n;
      EXPECT_EQ(m.connectivity, ref.connectivity) << n;
      ASSERT_EQ(m.point_fields.size(), ref.point_fields.size());
      for (std::size_t f = 0; f < m.point_fields.size(); ++f)
        EXPECT_EQ(m.point_fields[f].values, ref.point_fields[f].values) << m.point_fields[f].name;
    }
  }
}

TEST(Contour, BitIdenticalAcrossThreadCounts) {
  const ImageGrid g = generate::spherical_distance(70);
  ContourOptions opt;
  opt.isovalues = {30.1};
  opt.normals = ContourNormals::Average;
  std::vector<SurfaceMesh> meshes;
  for (int threads : {1, 2, 3, 4}) {
    parallel::set_thread_count(threads);
    meshes.push_back(generate::contour(g, opt));
  }
  parallel::set_thread_count(0);
  for (std::size_t i = 1; i < meshes.size(); ++i) {
    EXPECT_EQ(meshes[i].points, meshes[0].points);
    EXPECT_EQ(meshes[i].connectivity, meshes[0].connectivity);
    ASSERT_EQ(meshes[i].point_fields.size(), meshes[0].point_fields.size());
    for (std::size_t f = 0; f < meshes[0].point_fields.size(); ++f)
      EXPECT_EQ(meshes[i].point_fields[f].values, meshes[0].point_fields[f].values);
  }
}

TEST(Contour, EveryScalarTypeGivesTheSameSurface) {
  // Integer-valued samples: each type holds them exactly, so all agree.
  // n = 70 has whole 64-sample words and a tail in every row (classify
  // compares words of uint8 and float with SIMD, the tail padded); its
  // sphere crosses both.
  for (const Id n : {Id{20}, Id{70}}) {
    ImageGrid f32 = generate::spherical_distance(n);
    auto make = [&](ScalarType type) {
      ImageGrid g;
      g.allocate({n, n, n}, type);
      const float* src = static_cast<const float*>(f32.data());
      visit_scalars(g, [&](const auto* dst_const) {
        using T = std::remove_cv_t<std::remove_pointer_t<decltype(dst_const)>>;
        T* dst = const_cast<T*>(dst_const);
        for (Id i = 0; i < g.num_points(); ++i) dst[i] = static_cast<T>(std::floor(src[i]));
        return 0;
      });
      return g;
    };
    ContourOptions opt;
    opt.isovalues = {n == 20 ? 6.5 : 30.5};
    opt.scalars = false;
    const SurfaceMesh ref = generate::contour(make(ScalarType::Float64), opt);
    EXPECT_GT(ref.num_cells(), 100);
    for (auto type : {ScalarType::UInt8, ScalarType::Int8, ScalarType::UInt16, ScalarType::Int16, ScalarType::Int32,
                      ScalarType::Float32}) {
      const SurfaceMesh m = generate::contour(make(type), opt);
      EXPECT_EQ(m.points, ref.points) << scalar_type_name(type);
      EXPECT_EQ(m.connectivity, ref.connectivity) << scalar_type_name(type);
    }
  }
}

TEST(Contour, NaNSamplesAreOutsideAndNeverMakeNaNPoints) {
  ImageGrid g = generate::spherical_distance(16);
  float* v = static_cast<float*>(g.data());
  for (Id i = 0; i < g.num_points(); i += 7) v[i] = std::numeric_limits<float>::quiet_NaN();
  ContourOptions opt;
  opt.isovalues = {5.5};
  opt.normals = ContourNormals::Gradient;
  const SurfaceMesh m = generate::contour(g, opt);
  EXPECT_EQ(m.num_points(), straddling_edges(g, 5.5));
  for (float x : m.points) ASSERT_TRUE(std::isfinite(x));
  for (const auto& f : m.point_fields)
    for (float x : f.values) ASSERT_TRUE(std::isfinite(x)) << f.name;
}

TEST(Contour, IsovalueOutsideRangeGivesEmptyMesh) {
  const ImageGrid g = generate::spherical_distance(8);
  ContourOptions opt;
  opt.isovalues = {1000.0};
  const SurfaceMesh m = generate::contour(g, opt);
  EXPECT_EQ(m.num_points(), 0);
  EXPECT_EQ(m.num_cells(), 0);
}

TEST(Contour, RefusesBadArguments) {
  const ImageGrid g = generate::spherical_distance(8);
  ContourOptions opt;
  EXPECT_THROW(generate::contour(g, opt), InputError);
  opt.isovalues = {std::numeric_limits<double>::quiet_NaN()};
  EXPECT_THROW(generate::contour(g, opt), InputError);
  ImageGrid flat;
  flat.allocate({5, 5, 1}, ScalarType::Float32);
  opt.isovalues = {0.5};
  EXPECT_THROW(generate::contour(flat, opt), InputError);
}

// The paper's Table 1 (triangles) and the welded point counts, from an
// edge-based marching cubes on the Spherical Distance field at N/2 - 1 + 0.001.
// The point count is also checked against the brute-force straddling-edge count.
TEST(Contour, PaperTable1) {
  struct Row {
    Id n, points, triangles;
  };
  for (const Row& row : {Row{128, 74715, 149420}, Row{256, 303699, 607388}, Row{512, 1225611, 2451212}}) {
    const ImageGrid g = generate::spherical_distance(row.n);
    ContourOptions opt;
    opt.isovalues = {double(row.n) / 2 - 1 + 0.001};
    opt.scalars = false;
    const SurfaceMesh m = generate::contour(g, opt);
    EXPECT_EQ(m.num_points(), row.points) << row.n;
    EXPECT_EQ(m.num_cells(), row.triangles) << row.n;
    if (row.n <= 256) {
      EXPECT_EQ(m.num_points(), straddling_edges(g, opt.isovalues[0])) << row.n;
    }
  }
}

TEST(Contour, NoiseVolumeGivesAManifoldSurface) {
  // Independent random samples make every cube case, ambiguous faces
  // included, appear many times. Neighbouring cubes must never draw the same
  // diagonal across their shared face (an edge with four triangles), and no
  // edge may be open except on the grid's border.
  const ImageGrid g = keymesh::testing::uniform_noise({40, 37, 33}, 3, 0, 1);
  const float* v = static_cast<const float*>(g.data());
  std::set<unsigned> cases;
  for (Id k = 0; k + 1 < 33; ++k)
    for (Id j = 0; j + 1 < 37; ++j)
      for (Id i = 0; i + 1 < 40; ++i) {
        unsigned c = 0;
        for (int b = 0; b < 8; ++b)
          c |= unsigned(v[(i + (b & 1)) + 40 * ((j + ((b >> 1) & 1)) + 37 * (k + ((b >> 2) & 1)))] >= 0.5f) << b;
        cases.insert(c);
      }
  EXPECT_EQ(cases.size(), 256u);
  ContourOptions opt;
  opt.isovalues = {0.5};
  const SurfaceMesh m = generate::contour(g, opt);
  Id open_inside = 0, four = 0;
  for (const auto& [edge, n] : edge_use(m)) {
    four += n > 2;
    if (n == 1) {
      const float* a = &m.points[3 * edge.first];
      const float* b = &m.points[3 * edge.second];
      const float hi[3] = {39, 36, 32};
      bool border = false;
      for (int x = 0; x < 3; ++x) border = border || (a[x] == b[x] && (a[x] == 0 || a[x] == hi[x]));
      open_inside += !border;
    }
  }
  EXPECT_EQ(four, 0);
  EXPECT_EQ(open_inside, 0);
}

// The structured plan (count, scan, write: no soup) must give the sort plan's
// mesh array for array: same ids, points, triangles and fields, for every
// field option, several isovalues, slabs with ghost planes (global keys) and
// row lengths around the 64-bit word borders of the inside bits.
// The structured plan's count pass keeps the cube cases of a brick's cut
// voxels in room bounded by its rows' cut edges, for the write pass: on
// flat rows with a few spikes (far apart, at a row's ends, at word
// boundaries) the bound is tight and most rows have none; the same mesh as
// the sort plan, a point per straddling edge.
TEST(Contour, StructuredPlanOnSparseSpikesEqualsSortPlan) {
  for (const Id nx : {Id{256}, Id{257}, Id{700}, Id{1500}}) {
    ImageGrid g;
    g.allocate({nx, 5, 4}, ScalarType::Float32);
    auto* v = static_cast<float*>(g.data());
    std::fill(v, v + g.num_points(), 0.0f);
    std::mt19937 rng(static_cast<unsigned>(nx));
    for (int s = 0; s < 12; ++s) v[static_cast<Id>(rng() % static_cast<unsigned>(g.num_points()))] = 1;
    for (const Id i : {Id{0}, Id{63}, Id{64}, Id{254}, Id{256}, Id{511}, Id{600}, nx - 1})
      if (i < nx) v[i + nx * (2 + 5 * 1)] = 1;
    for (int threads : {1, 2}) {
      parallel::set_thread_count(threads);
      ContourOptions opt;
      opt.isovalues = {0.5};
      const SurfaceMesh rows = generate::contour(g, opt);
      opt.weld = ContourWeld::KeyReduceSort;
      const SurfaceMesh sort = generate::contour(g, opt);
      EXPECT_EQ(rows.num_points(), straddling_edges(g, 0.5)) << nx;
      EXPECT_EQ(rows.points, sort.points) << nx;
      EXPECT_EQ(rows.connectivity, sort.connectivity) << nx;
    }
  }
  parallel::set_thread_count(0);
}

// ContourOptions::output_arrays: the caller's arrays get every byte the
// mesh's vectors get (arrays filled with NaN and ~0 first, so an element
// left unwritten shows), and the mesh returned holds none of them; options
// the arrays do not cover are refused.
TEST(Contour, OutputArraysGetTheBytesOfTheMeshsVectors) {
  ImageGrid g = keymesh::testing::uniform_noise({37, 29, 23}, 3, 0, 1);
  g.spacing = {0.5, 1.25, 2.0};
  g.origin = {-3, 1, 7};
  for (bool scalars : {true, false})
    for (int threads : {1, 2}) {
      parallel::set_thread_count(threads);
      ContourOptions opt;
      opt.isovalues = {0.3, 0.62};
      opt.scalars = scalars;
      const SurfaceMesh ref = generate::contour(g, opt);
      Array<float> xyz, scalar;
      Array<PointIndex> ids;
      opt.output_arrays = [&](Id n, Id m) {
        xyz.assign(static_cast<std::size_t>(3 * n), std::numeric_limits<float>::quiet_NaN());
        scalar.assign(static_cast<std::size_t>(n), std::numeric_limits<float>::quiet_NaN());
        ids.assign(static_cast<std::size_t>(3 * m), ~PointIndex{0});
        return generate::ContourArrays{xyz.data(), ids.data(), scalars ? scalar.data() : nullptr};
      };
      const SurfaceMesh out = generate::contour(g, opt);
      EXPECT_TRUE(out.points.empty() && out.connectivity.empty() && out.point_fields.empty());
      EXPECT_EQ(xyz, ref.points) << scalars << threads;
      EXPECT_EQ(ids, ref.connectivity) << scalars << threads;
      if (scalars) {
        ASSERT_EQ(ref.point_fields.size(), 1u);
        EXPECT_EQ(scalar, ref.point_fields[0].values) << threads;
      }
      auto refused = [&](auto change) {
        ContourOptions bad = opt;
        change(bad);
        EXPECT_THROW(generate::contour(g, bad), InputError);
      };
      refused([](ContourOptions& o) { o.coarsen = true; });
      refused([](ContourOptions& o) { o.curvature = true; });
      refused([](ContourOptions& o) { o.normals = ContourNormals::Gradient; });
      refused([](ContourOptions& o) { o.normals = ContourNormals::Average; });
      refused([](ContourOptions& o) { o.weld = ContourWeld::KeyReduceSort; });
    }
  parallel::set_thread_count(0);
}

TEST(Contour, StructuredPlanEqualsSortPlanOnNoise) {
  std::mt19937 rng(11);
  for (const std::array<Id, 3> dims : {std::array<Id, 3>{2, 2, 2}, {63, 5, 4}, {64, 6, 5}, {65, 7, 6}, {129, 4, 9},
                                       {130, 9, 3}, {31, 33, 35}}) {
    ImageGrid g;
    g.allocate(dims, ScalarType::Float32);
    keymesh::testing::fill_uniform(g, rng, 0, 1);
    g.spacing = {0.5, 1.25, 2.0};
    g.origin = {-3, 1, 7};
    for (auto normals : {ContourNormals::None, ContourNormals::Gradient, ContourNormals::Average}) {
      for (int variant = 0; variant < 3; ++variant) {
        // Coarsened, and not: with and without scalars (positions alone
        // take a writer of their own).
        const bool coarsen = variant == 2;
        ContourOptions opt;
        opt.scalars = variant != 1;
        opt.isovalues = {0.5, 0.21, 0.77};
        opt.normals = normals;
        opt.curvature = normals == ContourNormals::Gradient;
        opt.coarsen = coarsen;
        const SurfaceMesh rows = generate::contour(g, opt);
        opt.weld = ContourWeld::KeyReduceSort;
        const SurfaceMesh sort = generate::contour(g, opt);
        const std::string where = std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" +
                                  std::to_string(dims[2]) + " variant " + std::to_string(variant);
        if (!coarsen) {
          EXPECT_EQ(rows.num_points(),
                    straddling_edges(g, 0.5) + straddling_edges(g, 0.21) + straddling_edges(g, 0.77)) << where;
        }
        EXPECT_EQ(rows.points, sort.points) << where;
        EXPECT_EQ(rows.connectivity, sort.connectivity) << where;
        ASSERT_EQ(rows.point_fields.size(), sort.point_fields.size()) << where;
        for (std::size_t f = 0; f < rows.point_fields.size(); ++f)
          EXPECT_EQ(rows.point_fields[f].values, sort.point_fields[f].values) << where << rows.point_fields[f].name;
      }
    }
    if (dims[2] < 4) continue;
    // A slab of planes [1, nz - 1) with one ghost plane on either side: the
    // same mesh and global keys from both plans.
    ImageGrid slab = g;
    ContourOptions opt;
    opt.isovalues = {0.5, 0.3};
    opt.normals = ContourNormals::Gradient;
    opt.first_plane = 3;
    opt.total_planes = dims[2] + 5;
    opt.ghost_below = 1;
    opt.ghost_above = 1;
    std::vector<std::uint64_t> keys_rows, keys_sort;
    const SurfaceMesh rows = generate::contour(slab, opt, nullptr, &keys_rows);
    opt.weld = ContourWeld::KeyReduceSort;
    const SurfaceMesh sort = generate::contour(slab, opt, nullptr, &keys_sort);
    EXPECT_EQ(keys_rows, keys_sort);
    EXPECT_TRUE(std::is_sorted(keys_rows.begin(), keys_rows.end()));
    EXPECT_EQ(rows.points, sort.points);
    EXPECT_EQ(rows.connectivity, sort.connectivity);
    EXPECT_EQ(rows.point_fields[1].values, sort.point_fields[1].values);
  }
}
