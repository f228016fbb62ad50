#include "keymesh/generate/labels/labels_multilod.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "keymesh/core/error.hpp"
#include "label_map.hpp"
#include "mesh_measures.hpp"

using namespace keymesh;
using generate::MultilodPiece;
using generate::MultilodOptions;
using test::label_map;

namespace {

// Two overlapping balls (labels 3 and 7, touching where they meet) and a
// box of label 9 across a chunk corner.
ImageGrid balls(Id n) {
  return label_map({n, n + 3, n - 2}, [&](Id i, Id j, Id k) {
    auto in = [&](double cx, double cy, double cz, double r) {
      return (i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz) <= r * r;
    };
    if (in(0.4 * n, 0.45 * n, 0.5 * n, 0.3 * n)) return 3;
    if (in(0.65 * n, 0.55 * n, 0.45 * n, 0.25 * n)) return 7;
    if (i >= 5 && i < 10 && j >= 5 && j < 9 && k >= 6 && k < 8) return 9;
    return 0;
  });
}

// White noise of labels 0-3 (thin, touching, self-touching regions).
ImageGrid noise(Id n, unsigned seed) {
  std::mt19937 rng(seed);
  return label_map({n, n - 1, n + 1}, [&](Id, Id, Id) { return static_cast<int>(rng() % 4); });
}

MultilodOptions options(generate::LabelMethod method, int smooth, Id chunk, int lods) {
  MultilodOptions o;
  o.labels.method = method;
  o.labels.smooth_iterations = smooth;
  o.chunk_shape = {chunk, chunk, chunk};
  o.lods = lods;
  return o;
}

using PieceId = std::tuple<std::uint64_t, std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>;
PieceId id_of(const MultilodPiece& p) { return {p.segment, p.lod, p.chunk[0], p.chunk[1], p.chunk[2]}; }

std::uint32_t bits(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}

// (key, position bits) of the piece's points lying on the plane `axis` = x,
// those on the face's border lines (chunk edge lines, shared by four chunks)
// included.
std::set<std::tuple<std::uint64_t, std::uint32_t, std::uint32_t, std::uint32_t>> on_plane(const MultilodPiece* p, int axis,
                                                                                         double x) {
  std::set<std::tuple<std::uint64_t, std::uint32_t, std::uint32_t, std::uint32_t>> out;
  if (!p) return out;
  for (std::size_t i = 0; i < p->point_keys.size(); ++i)
    if (p->points[3 * i + axis] == x)
      out.emplace(p->point_keys[i], bits(p->points[3 * i]), bits(p->points[3 * i + 1]), bits(p->points[3 * i + 2]));
  return out;
}

// The piece's boundary edges on the plane `axis` = x: net directed edges
// (smaller key first, times `sign`) between points on it, zeros left out.
std::map<std::pair<std::uint64_t, std::uint64_t>, int> face_boundary(const MultilodPiece* q, int axis, double x,
                                                                    int sign) {
  std::map<std::pair<std::uint64_t, std::uint64_t>, int> net;
  if (!q) return net;
  for (std::size_t t = 0; t < q->triangles.size(); t += 3)
    for (int m = 0; m < 3; ++m) {
      const auto u = q->triangles[t + m], v = q->triangles[t + (m + 1) % 3];
      if (q->points[3 * u + axis] != x || q->points[3 * v + axis] != x) continue;
      const auto ku = q->point_keys[u], kv = q->point_keys[v];
      net[{std::min(ku, kv), std::max(ku, kv)}] += ku < kv ? sign : -sign;
    }
  for (auto e = net.begin(); e != net.end();) e = e->second == 0 ? net.erase(e) : std::next(e);
  return net;
}

// Every piece inside its chunk's box, no repeated point in a triangle, keys
// increasing; neighbouring chunks' pieces with the same points (keys and
// bits) on their common face.
void expect_chunks_agree(const std::vector<MultilodPiece>& pieces, const generate::MultilodGrid& grid) {
  std::map<PieceId, const MultilodPiece*> by_id;
  for (const MultilodPiece& p : pieces) by_id[id_of(p)] = &p;
  Id faces_with_points = 0, coarse_line_points = 0;
  for (const MultilodPiece& p : pieces) {
    for (std::size_t i = 0; i < p.point_keys.size(); ++i) {
      if (i > 0) {
        ASSERT_LT(p.point_keys[i - 1], p.point_keys[i]);
      }
      for (int a = 0; a < 3; ++a) {
        ASSERT_GE(p.points[3 * i + a], grid.plane(a, p.chunk[a])) << "class " << (p.point_keys[i] >> 61) << " lod " << p.lod << " axis " << a << " " << p.points[3*i] << " " << p.points[3*i+1] << " " << p.points[3*i+2];
        ASSERT_LE(p.points[3 * i + a], grid.plane(a, p.chunk[a] + 1));
      }
    }
    // Off the chunk planes by the level's margin (never rounded onto a face
    // by the writer's quantization), or on one.
    for (std::size_t i = 0; i < p.points.size(); ++i) {
      const int a = static_cast<int>(i % 3);
      const double cs = static_cast<double>(grid.chunk_shape[a]);
      const double d = std::abs(p.points[i] - (grid.grid_origin[a] + cs * std::round((p.points[i] - grid.grid_origin[a]) / cs)));
      ASSERT_TRUE(d == 0 || d >= 0.99 * grid.margin(a, static_cast<int>(p.lod))) << d << " lod " << p.lod;
    }
    std::vector<char> used(p.point_keys.size(), 0);
    for (std::uint32_t c : p.triangles) used[c] = 1;
    for (char u : used) ASSERT_TRUE(u);  // the writer's Draco fragments keep used points only
    for (std::size_t t = 0; t < p.triangles.size(); t += 3) {
      ASSERT_NE(p.triangles[t], p.triangles[t + 1]);
      ASSERT_NE(p.triangles[t + 1], p.triangles[t + 2]);
      ASSERT_NE(p.triangles[t], p.triangles[t + 2]);
    }
    for (int a = 0; a < 3; ++a) {
      if (p.chunk[a] + 1 >= static_cast<std::uint32_t>(grid.chunks[a])) continue;
      PieceId next = id_of(p);
      ++(a == 0 ? std::get<2>(next) : a == 1 ? std::get<3>(next) : std::get<4>(next));
      const auto it = by_id.find(next);
      const double x = grid.plane(a, p.chunk[a] + 1);
      const auto mine = on_plane(&p, a, x);
      const auto theirs = on_plane(it == by_id.end() ? nullptr : it->second, a, x);
      EXPECT_EQ(mine, theirs) << "segment " << p.segment << " lod " << p.lod << " chunk " << p.chunk[0] << " "
                              << p.chunk[1] << " " << p.chunk[2] << " axis " << a;
      // The boundaries on the face: opposite.
      EXPECT_EQ(face_boundary(&p, a, x, 1), face_boundary(it == by_id.end() ? nullptr : it->second, a, x, -1))
          << "boundary lod " << p.lod;
      faces_with_points += mine.empty() ? 0 : 1;
      for (const auto& point : mine) coarse_line_points += p.lod > 0 && std::get<0>(point) >> 61 >= 4 ? 1 : 0;
    }
  }
  EXPECT_GT(faces_with_points, 0);  // the volumes cross chunk faces
  EXPECT_GT(coarse_line_points, 0);  // and chunk edge lines at lod > 0
}

// Each segment's pieces of one level, welded by key: a closed 2-cycle (every
// directed edge as often as its reverse). Returns the enclosed volume per segment.
std::map<std::uint64_t, double> expect_closed(const std::vector<MultilodPiece>& pieces, std::uint32_t lod) {
  std::map<std::uint64_t, std::map<std::pair<std::uint64_t, std::uint64_t>, int>> edges;
  std::map<std::uint64_t, double> volume;
  for (const MultilodPiece& p : pieces) {
    if (p.lod != lod) continue;
    auto& e = edges[p.segment];
    for (std::size_t t = 0; t < p.triangles.size(); t += 3) {
      for (int m = 0; m < 3; ++m)
        ++e[{p.point_keys[p.triangles[t + m]], p.point_keys[p.triangles[t + (m + 1) % 3]]}];
      const float* a = &p.points[3 * p.triangles[t]];
      const float* b = &p.points[3 * p.triangles[t + 1]];
      const float* c = &p.points[3 * p.triangles[t + 2]];
      volume[p.segment] += (double(a[0]) * (double(b[1]) * c[2] - double(b[2]) * c[1]) -
                            double(a[1]) * (double(b[0]) * c[2] - double(b[2]) * c[0]) +
                            double(a[2]) * (double(b[0]) * c[1] - double(b[1]) * c[0])) / 6.0;
    }
  }
  for (const auto& [segment, e] : edges)
    for (const auto& [edge, count] : e) {
      const auto back = e.find({edge.second, edge.first});
      EXPECT_EQ(count, back == e.end() ? 0 : back->second) << "segment " << segment << " lod " << lod;
    }
  return volume;
}

void expect_same_pieces(const std::vector<MultilodPiece>& a, const std::vector<MultilodPiece>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(id_of(a[i]), id_of(b[i]));
    EXPECT_EQ(a[i].point_keys, b[i].point_keys);
    EXPECT_EQ(a[i].triangles, b[i].triangles);
    ASSERT_EQ(a[i].points.size(), b[i].points.size());
    EXPECT_EQ(std::memcmp(a[i].points.data(), b[i].points.data(), 4 * a[i].points.size()), 0);
  }
}

std::vector<MultilodPiece> of_chunk(const std::vector<MultilodPiece>& pieces, const std::array<Id, 3>& c) {
  std::vector<MultilodPiece> out;
  for (const MultilodPiece& p : pieces)
    if (p.chunk[0] == c[0] && p.chunk[1] == c[1] && p.chunk[2] == c[2]) out.push_back(p);
  return out;
}

}  // namespace

TEST(LabelsMultilod, GridCoversThePaddedSurface) {
  const auto g = generate::multilod_grid({64, 63, 10}, options(generate::LabelMethod::SurfaceNets, 0, 32, 3));
  EXPECT_EQ(g.chunks, (std::array<Id, 3>{3, 2, 1}));  // [-1, 64] needs 66 > 64 samples
  EXPECT_EQ(g.plane(0, 1), 31.0);
}

TEST(LabelsMultilod, ChunksAgreeOnFacesAtEveryLevel) {
  for (auto method : {generate::LabelMethod::SurfaceNets, generate::LabelMethod::DiscreteMarchingCubes})
    for (const ImageGrid& g : {balls(24), noise(14, 1)}) {
      const MultilodOptions o = options(method, 16, 8, 3);
      const auto pieces = generate::multilod_pieces(g, o);
      ASSERT_FALSE(pieces.empty());
      expect_chunks_agree(pieces, generate::multilod_grid(g.dims, o));
      for (std::uint32_t lod = 0; lod < 3; ++lod) expect_closed(pieces, lod);
    }
}

// Level 0 welded by key is the segment's per-label surface cut at the chunk
// planes: every point of it, the same enclosed volume.
TEST(LabelsMultilod, LevelZeroIsThePerLabelSurface) {
  for (auto method : {generate::LabelMethod::SurfaceNets, generate::LabelMethod::DiscreteMarchingCubes}) {
    const ImageGrid g = balls(24);
    const MultilodOptions o = options(method, 16, 8, 2);
    const auto pieces = generate::multilod_pieces(g, o);
    const auto volume = expect_closed(pieces, 0);
    generate::LabelOptions whole = o.labels;
    whole.per_label = true;
    const SurfaceMesh mesh = generate::contour_labels(g, whole);
    const Field* label = mesh.find_cell_field("label");
    ASSERT_NE(label, nullptr);
    std::map<std::uint64_t, double> expected;
    std::map<std::uint64_t, std::set<PointIndex>> points;
    for (Id t = 0; t < mesh.num_cells(); ++t) {
      const auto s = static_cast<std::uint64_t>(label->values[t]);
      SurfaceMesh one;
      one.points = mesh.points;
      one.connectivity.assign(mesh.connectivity.begin() + 3 * t, mesh.connectivity.begin() + 3 * t + 3);
      expected[s] += test::enclosed_volume(one);
      for (int m = 0; m < 3; ++m) points[s].insert(mesh.connectivity[3 * t + m]);
    }
    std::map<std::uint64_t, std::set<std::uint64_t>> surface_keys;  // class 0: the surface's own points
    for (const MultilodPiece& p : pieces)
      if (p.lod == 0)
        for (std::uint64_t k : p.point_keys)
          if (k >> 61 == 0) surface_keys[p.segment].insert(k);
    ASSERT_EQ(volume.size(), expected.size());
    for (const auto& [s, v] : expected) {
      EXPECT_NEAR(volume.at(s), v, 1e-4 * std::abs(v)) << "segment " << s;
      EXPECT_EQ(surface_keys[s].size(), points[s].size()) << "segment " << s;
    }
  }
}

// A chunk task (its box and halo only) gives the one-call run's pieces bit
// for bit.
TEST(LabelsMultilod, ChunkTaskEqualsOneCall) {
  for (auto method : {generate::LabelMethod::SurfaceNets, generate::LabelMethod::DiscreteMarchingCubes}) {
    const ImageGrid g = noise(40, 2);
    const MultilodOptions o = options(method, 3, 8, 3);
    const auto all = generate::multilod_pieces(g, o);
    const auto grid = generate::multilod_grid(g.dims, o);
    ASSERT_LT(8 + 2 * generate::multilod_halo(o), 40);  // the tasks read a part of the volume
    for (Id z = 0; z < grid.chunks[2]; ++z)
      for (Id y = 0; y < grid.chunks[1]; ++y)
        for (Id x = (y + z) % 3; x < grid.chunks[0]; x += 3)  // a third of them, borders and inside
          expect_same_pieces(generate::multilod_chunk_pieces(g, o, {x, y, z}), of_chunk(all, {x, y, z}));
  }
}

// Chunks out of reach of a change keep their pieces; so an update recomputes
// multilod_affected_chunks only.
TEST(LabelsMultilod, ChangeReachesOnlyAffectedChunks) {
  const ImageGrid before = balls(40);
  ImageGrid after = before;
  auto* v = reinterpret_cast<std::uint8_t*>(after.data());
  for (Id k = 15; k < 23; ++k)  // chunk (2, 2, 2) of 8: samples 15 .. 22
    for (Id j = 15; j < 23; ++j)
      for (Id i = 15; i < 23; ++i) v[i + after.dims[0] * (j + after.dims[1] * k)] = (i + j + k) % 3 ? 7 : 0;
  const MultilodOptions o = options(generate::LabelMethod::SurfaceNets, 3, 8, 2);
  const auto grid = generate::multilod_grid(before.dims, o);
  const auto affected = generate::multilod_affected_chunks(grid, o, {{2, 2, 2}});
  // The halo, 2 x 3 smoothing iterations (the fold guard reads one cell
  // further) + 4 = 10 samples, reaches two 8-sample chunks each way.
  EXPECT_EQ(affected.size(), 125u);
  const auto old_pieces = generate::multilod_pieces(before, o), new_pieces = generate::multilod_pieces(after, o);
  Id changed = 0;
  for (Id z = 0; z < grid.chunks[2]; ++z)
    for (Id y = 0; y < grid.chunks[1]; ++y)
      for (Id x = 0; x < grid.chunks[0]; ++x) {
        const std::array<Id, 3> c{x, y, z};
        const auto a = of_chunk(old_pieces, c), b = of_chunk(new_pieces, c);
        const bool near = std::find(affected.begin(), affected.end(), c) != affected.end();
        if (!near) expect_same_pieces(a, b);
        changed += near && a.size() != b.size() ? 1 : 0;
      }
  EXPECT_GT(changed, 0);
}

TEST(LabelsMultilod, Refusals) {
  const ImageGrid g = balls(16);
  MultilodOptions o = options(generate::LabelMethod::SurfaceNets, 2, 8, 2);
  o.labels.coarsen = true;
  EXPECT_THROW(generate::multilod_pieces(g, o), InputError);
  o.labels.coarsen = false;
  o.chunk_shape[1] = 1;
  EXPECT_THROW(generate::multilod_pieces(g, o), InputError);
  o.chunk_shape[1] = 8;
  EXPECT_THROW(generate::multilod_chunk_pieces(g, o, {0, 3, 0}), InputError);
  EXPECT_THROW(generate::multilod_affected_chunks(generate::multilod_grid(g.dims, o), o, {{-1, 0, 0}}), InputError);
  ImageGrid s;
  s.allocate({4, 4, 4}, ScalarType::Int8);
  reinterpret_cast<std::int8_t*>(s.data())[21] = -3;
  EXPECT_THROW(generate::multilod_pieces(s, o), InputError);
}

// Many noise volumes, chunk shapes that 2^lod does not divide, both methods.
TEST(LabelsMultilod, NoiseStress) {
  for (unsigned seed = 3; seed < 15; ++seed)
    for (auto method : {generate::LabelMethod::SurfaceNets, generate::LabelMethod::DiscreteMarchingCubes}) {
      const ImageGrid g = noise(13 + seed % 5, seed);
      MultilodOptions o = options(method, seed % 2 ? 16 : 5, 4 + seed % 4, 4);
      o.chunk_shape[1] = 5;
      const auto pieces = generate::multilod_pieces(g, o);
      expect_chunks_agree(pieces, generate::multilod_grid(g.dims, o));
      for (std::uint32_t lod = 0; lod < 4; ++lod) expect_closed(pieces, lod);
    }
}
