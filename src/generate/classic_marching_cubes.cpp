#include "keymesh/generate/classic_marching_cubes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/core/free_storage.hpp"
#include "keymesh/core/progress.hpp"
#include "keymesh/generate/marching_cubes_table.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh::generate {

namespace {

// Corner k of the classic numbering as (dx, dy, dz).
constexpr int kCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                               {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
// The two corners of classic edge e, in the order scikit-image adds their
// gradients (it matters for float32 sums): round each z face, then upwards.
constexpr int kEdge[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                              {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
// scikit-image's epsilon: numpy.spacing(1.0), the double machine epsilon.
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

int edge_axis(int e) {
  for (int a = 0; a < 3; ++a)
    if (kCorner[kEdge[e][0]][a] != kCorner[kEdge[e][1]][a]) return a;
  return -1;
}

// The weight of a corner whose value minus the level is v.
double corner_weight(double v) { return 1.0 / (kEpsilon + std::fabs(v)); }

struct Lattice {
  Id n0, n1, n2;   // array shape; x = axis 2
  Id step;
  Id cx, cy, cz;   // cubes along x, y, z
  Id px, py, pz;   // coarse points along x, y, z (cubes + 1)

  Id sample(Id x, Id y, Id z) const { return (z * n1 + y) * n2 + x; }
  // The key of the coarse edge from coarse point (X, Y, Z) along `axis`.
  std::uint64_t edge_key(Id X, Id Y, Id Z, int axis) const {
    return 3 * static_cast<std::uint64_t>((Z * py + Y) * px + X) + static_cast<std::uint64_t>(axis);
  }
};

// The eight corner values of cube (x, y, z) (voxel coordinates of its first
// corner), minus the level, in classic corner order.
void cube_values(const float* volume, const Lattice& g, double level, Id x, Id y, Id z, double v[8]) {
  for (int k = 0; k < 8; ++k)
    v[k] = static_cast<double>(volume[g.sample(x + g.step * kCorner[k][0], y + g.step * kCorner[k][1],
                                               z + g.step * kCorner[k][2])]) -
           level;
}

// The case of cube (X, Y, Z) (coarse coordinates) from the per-point
// inside bytes: value - level > 0, which for doubles is value > level.
int cube_case(const std::vector<std::uint8_t>& above, const Lattice& g, Id X, Id Y, Id Z) {
  int c = 0;
  for (int k = 0; k < 8; ++k)
    c |= above[static_cast<std::size_t>(((Z + kCorner[k][2]) * g.py + Y + kCorner[k][1]) * g.px + X + kCorner[k][0])]
         << k;
  return c;
}

bool cube_kept(const Lattice& g, const ClassicMarchingCubesOptions& o, Id x, Id y, Id z) {
  return o.mask == nullptr || o.mask[g.sample(x + g.step, y + g.step, z + g.step)] != 0;
}

int triangle_count(const ClassicTable& table, int c) {
  int n = 0;
  while (n < 5 && table[c][3 * n] >= 0) ++n;
  return n;
}

// The classic corner index of a corner given as a bit index (x | y << 1 | z << 2).
int classic_corner_of_bits(int bits) {
  for (int k = 0; k < 8; ++k)
    if ((kCorner[k][0] | kCorner[k][1] << 1 | kCorner[k][2] << 2) == bits) return k;
  return -1;
}

// parallel::for_each over [0, n) in up to 8 consecutive blocks, reporting
// `stage` after each (at fractions f0..f1), so that a large volume's long
// stages can be followed and abandoned between blocks (core/progress.hpp:
// never from inside the parallel loop). Same work, same result.
template <class F>
void for_each_reporting(Id n, const char* stage, double f0, double f1, Id min_per_chunk, F&& f) {
  const Id blocks = std::clamp<Id>(n / 256, 1, 8);
  for (Id b = 0; b < blocks; ++b) {
    const Id lo = n * b / blocks, hi = n * (b + 1) / blocks;
    parallel::for_each(hi - lo, [&](Id i) { f(lo + i); }, min_per_chunk);
    progress::report(stage, f0 + (f1 - f0) * static_cast<double>(b + 1) / static_cast<double>(blocks));
  }
}

}  // namespace

ClassicTable classic_table() {
  const MarchingCubesTable& t = marching_cubes_table();
  // keymesh edge -> classic edge, by their corners.
  int edge_map[12];
  for (int e = 0; e < 12; ++e) {
    const int a = classic_corner_of_bits(t.edges[e].corner0), b = classic_corner_of_bits(t.edges[e].corner1);
    for (int c = 0; c < 12; ++c)
      if ((kEdge[c][0] == a && kEdge[c][1] == b) || (kEdge[c][0] == b && kEdge[c][1] == a)) edge_map[e] = c;
  }
  ClassicTable out;
  for (auto& row : out) row.fill(-1);
  for (int classic_case = 0; classic_case < 256; ++classic_case) {
    int keymesh_case = 0;
    for (int k = 0; k < 8; ++k)
      if ((classic_case >> k) & 1) keymesh_case |= 1 << (kCorner[k][0] | kCorner[k][1] << 1 | kCorner[k][2] << 2);
    // keymesh's triangles face the outside; the classic table's (as
    // scikit-image reads it, before its "descent" flip) face the inside.
    for (int tri = 0; tri < t.triangle_count[keymesh_case]; ++tri)
      for (int k = 0; k < 3; ++k)
        out[classic_case][3 * tri + k] =
            static_cast<std::int8_t>(edge_map[t.triangle_edges[keymesh_case][3 * tri + 2 - k]]);
  }
  return out;
}

namespace {

// One call's state: the lattice, the options and the steps' results.
struct ClassicRun {
  const float* volume;
  const ClassicTable& table;
  const ClassicMarchingCubesOptions& o;
  Lattice g;
  double level;
  std::vector<std::uint8_t> above;         // 0: inside byte per coarse point
  std::vector<std::uint64_t> row_first;    // 1: first triangle of each row of cubes
  std::uint64_t triangles = 0;
  std::vector<std::uint64_t> origin;       // 2: per corner, cube * 16 + classic edge
  keyreduce::Groups<std::uint64_t> groups; // 3: corners grouped by edge
  std::vector<std::int32_t> point_id;      // 4: scikit-image's point numbering

  Id rows() const { return g.cy * g.cz; }
  Id corners() const { return static_cast<Id>(3 * triangles); }

  // 0. Which coarse points are inside (one byte each): the cases below are
  // read from these instead of from eight samples per cube, twice.
  void classify_points() {
    above.resize(static_cast<std::size_t>(g.px * g.py * g.pz));
    parallel::for_each(g.py * g.pz, [&](Id r) {
      const Id Y = r % g.py, Z = r / g.py;
      std::uint8_t* out = &above[static_cast<std::size_t>(r * g.px)];
      const float* in = volume + g.sample(0, Y * g.step, Z * g.step);
      for (Id X = 0; X < g.px; ++X) out[X] = static_cast<double>(in[X * g.step]) > level ? 1 : 0;
    }, 16);
  }

  // 1. Triangles per row of cubes (z, y), then their first index.
  void count_rows() {
    row_first.assign(static_cast<std::size_t>(rows()) + 1, 0);
    int triangles_of_case[256];
    for (int c = 0; c < 256; ++c) triangles_of_case[c] = triangle_count(table, c);
    for_each_reporting(rows(), "marching cubes: classify", 0.0, 0.25, 1, [&](Id r) {
      const Id Y = r % g.cy, Z = r / g.cy;
      std::uint64_t n = 0;
      for (Id X = 0; X < g.cx; ++X) {
        if (!cube_kept(g, o, X * g.step, Y * g.step, Z * g.step)) continue;
        n += static_cast<std::uint64_t>(triangles_of_case[cube_case(above, g, X, Y, Z)]);
      }
      row_first[r] = n;
    });
    triangles = parallel::exclusive_scan(row_first.data(), row_first.data(), rows());
    row_first[rows()] = triangles;
    constexpr std::uint64_t kMaxCorners = std::numeric_limits<std::int32_t>::max();
    if (3 * triangles > kMaxCorners)
      throw LimitError("marching cubes: " + std::to_string(triangles) +
                       " triangles exceed the 2^31 - 1 corners of int32 faces");
  }

  // 2. The soup, in scikit-image's order: every corner's edge key, and where
  // it came from (cube index * 16 + classic edge) for the reduction.
  std::vector<std::uint64_t> soup() {
    std::vector<std::uint64_t> keys(static_cast<std::size_t>(corners()));
    origin.resize(static_cast<std::size_t>(corners()));
    for_each_reporting(rows(), "marching cubes: generate", 0.25, 0.5, 1, [&](Id r) {
      const Id Y = r % g.cy, Z = r / g.cy;
      const Id y = Y * g.step, z = Z * g.step;
      std::uint64_t at = 3 * row_first[r];
      if (row_first[r + 1] == row_first[r]) return;
      for (Id X = 0; X < g.cx; ++X) {
        const Id x = X * g.step;
        if (!cube_kept(g, o, x, y, z)) continue;
        const auto& row = table[cube_case(above, g, X, Y, Z)];
        const std::uint64_t cube = static_cast<std::uint64_t>((Z * g.cy + Y) * g.cx + X);
        for (int k = 0; k < 15 && row[k - k % 3] >= 0; ++k) {
          const int e = row[k], a = kEdge[e][0], b = kEdge[e][1];
          const int lo = kCorner[a][edge_axis(e)] == 0 ? a : b;
          keys[at] = g.edge_key(X + kCorner[lo][0], Y + kCorner[lo][1], Z + kCorner[lo][2], edge_axis(e));
          origin[at] = cube * 16 + static_cast<std::uint64_t>(e);
          ++at;
        }
      }
    });
    return keys;
  }

  // 3. KEY-REDUCE: one group per edge; pairs in scan order within a group.
  // 4. Number the points by their first use, as scikit-image creates them:
  // group g's first pair is order[offsets[g]]; ranking those pair indices
  // is a scan over flags on the pairs.
  void weld(std::vector<std::uint64_t> keys) {
    const std::uint64_t key_range = 3 * static_cast<std::uint64_t>(g.px * g.py * g.pz);
    groups = keyreduce::partition_dense(keys.data(), corners(), key_range, keyreduce::Order::Build);
    free_storage(keys);
    free_storage(above);
    const Id points = groups.num_groups();
    if (points > static_cast<Id>(std::numeric_limits<std::int32_t>::max()))
      throw LimitError("marching cubes: " + std::to_string(points) + " points exceed int32 face indices");
    std::vector<std::uint32_t> first_use(static_cast<std::size_t>(corners()), 0);
    parallel::for_each(points, [&](Id p) { first_use[groups.order[groups.offsets[p]]] = 1; });
    parallel::exclusive_scan(first_use.data(), first_use.data(), corners());
    point_id.resize(static_cast<std::size_t>(points));
    parallel::for_each(points, [&](Id p) {
      point_id[p] = static_cast<std::int32_t>(first_use[groups.order[groups.offsets[p]]]);
    });
  }

  // Position of point p's edge crossing (x, y, z): scikit-image's base +
  // step * f / ff with ff the weight sum and f the far corner's weight along
  // the edge (the cross axes are whole numbers).
  void crossing(Id p, double xyz[3]) const {
    const std::uint64_t key = groups.unique_keys[p];
    const int axis = static_cast<int>(key % 3);
    const Id point = static_cast<Id>(key / 3);
    const Id P[3] = {point % g.px, (point / g.px) % g.py, point / (g.px * g.py)};
    Id lo[3] = {P[0] * g.step, P[1] * g.step, P[2] * g.step};
    Id hi[3] = {lo[0], lo[1], lo[2]};
    hi[axis] += g.step;
    const double w_lo = corner_weight(static_cast<double>(volume[g.sample(lo[0], lo[1], lo[2])]) - level);
    const double w_hi = corner_weight(static_cast<double>(volume[g.sample(hi[0], hi[1], hi[2])]) - level);
    const double ff = w_lo + w_hi;
    for (int a = 0; a < 3; ++a) xyz[a] = static_cast<double>(lo[a]);
    xyz[axis] += static_cast<double>(g.step) * w_hi / ff;
    // A NaN sample: scikit-image sums weight * offset on every axis, and
    // 0 * NaN is NaN, so the whole point is NaN, not just its edge axis.
    if (std::isnan(ff))
      for (int a = 0; a < 3; ++a) xyz[a] = std::numeric_limits<double>::quiet_NaN();
  }

  // Point p's normal (unnormalised, float sums in scikit-image's order) and
  // value from the cubes that use it. The gradient at a corner: per axis,
  // the difference along the cube edge through it, low side minus high side,
  // so it points to lower values. scikit-image takes the corner's weight
  // from the corner itself but its gradient from the corner whose classic
  // number equals the corner's x | y << 1 | z << 2 (so x is mirrored for the
  // corners with y = 1); reproduced as it is, being what its normals are.
  float normal_and_value(Id p, const int g_low[8][3], const int g_high[8][3], float n[3]) const {
    float value = 0;
    double v[8];
    for (Id i = groups.offsets[p]; i < groups.offsets[p + 1]; ++i) {
      const std::uint64_t from = origin[groups.order[i]];
      const int e = static_cast<int>(from % 16);
      const Id cube = static_cast<Id>(from / 16);
      const Id X = cube % g.cx, Y = (cube / g.cx) % g.cy, Z = cube / (g.cx * g.cy);
      cube_values(volume, g, level, X * g.step, Y * g.step, Z * g.step, v);
      double vmax = 0, vmin = 0;
      for (double s : v) {
        if (s > vmax) vmax = s;
        if (s < vmin) vmin = s;
      }
      value = std::max(value, static_cast<float>(vmax - vmin));
      for (int end = 0; end < 2; ++end) {
        const int c = kEdge[e][end];
        const float strength = static_cast<float>(corner_weight(v[c]));
        const int grad_corner = kCorner[c][0] | kCorner[c][1] << 1 | kCorner[c][2] << 2;
        for (int a = 0; a < 3; ++a) {
          const int c0 = g_low[grad_corner][a], c1 = g_high[grad_corner][a];
          n[a] += static_cast<float>((v[c0] - v[c1]) * static_cast<double>(strength));
        }
      }
    }
    return value;
  }

  // 5. Per point: position from its edge, normal and value from its corners.
  void points(ClassicMarchingCubes& out) const {
    const Id points = groups.num_groups();
    out.vertices.resize(static_cast<std::size_t>(3 * points));
    out.normals.resize(static_cast<std::size_t>(3 * points));
    out.values.resize(static_cast<std::size_t>(points));
    // For corner c and axis a: the corners at the low and high end of the
    // cube edge along a through c.
    int g_low[8][3], g_high[8][3];
    for (int c = 0; c < 8; ++c)
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 8; ++k) {
          bool same = true;
          for (int b = 0; b < 3; ++b)
            if (b != a && kCorner[k][b] != kCorner[c][b]) same = false;
          if (same) (kCorner[k][a] == 0 ? g_low[c][a] : g_high[c][a]) = k;
        }
    for_each_reporting(points, "marching cubes: points", 0.7, 0.95, 256, [&](Id p) {
      double xyz[3];
      crossing(p, xyz);
      float n[3] = {0, 0, 0};
      const float value = normal_and_value(p, g_low, g_high, n);
      double length = 0;
      for (float c : n) length += static_cast<double>(c) * static_cast<double>(c);
      if (length > 0) length = 1.0 / std::pow(length, 0.5);
      const std::size_t at = static_cast<std::size_t>(point_id[p]);
      for (int a = 0; a < 3; ++a) {
        // Array axis order: axis 0 is z.
        out.vertices[3 * at + a] = static_cast<float>(xyz[2 - a]);
        out.normals[3 * at + a] = static_cast<float>(static_cast<double>(n[2 - a]) * length);
      }
      out.values[at] = value;
    });
  }

  // 6. Faces: the index map renumbered; "descent" reverses every triangle.
  void faces(ClassicMarchingCubes& out) const {
    out.faces.resize(static_cast<std::size_t>(corners()));
    parallel::for_each(static_cast<Id>(triangles), [&](Id t) {
      for (int k = 0; k < 3; ++k) {
        const int from = o.descent ? 2 - k : k;
        out.faces[3 * t + k] = point_id[groups.index_map[3 * t + from]];
      }
    });
  }
};

}  // namespace

ClassicMarchingCubes classic_marching_cubes(const float* volume, std::array<Id, 3> shape, const ClassicTable& table,
                                            const ClassicMarchingCubesOptions& o) {
  if (shape[0] < 2 || shape[1] < 2 || shape[2] < 2)
    throw InputError("marching cubes needs at least 2x2x2 samples");
  if (o.step < 1) throw InputError("marching cubes step must be at least 1, got " + std::to_string(o.step));
  Lattice g{shape[0], shape[1], shape[2], o.step, 0, 0, 0, 0, 0, 0};
  g.cx = (g.n2 - 1) / g.step;
  g.cy = (g.n1 - 1) / g.step;
  g.cz = (g.n0 - 1) / g.step;
  g.px = g.cx + 1;
  g.py = g.cy + 1;
  g.pz = g.cz + 1;
  ClassicRun run{volume, table, o, g, o.level, {}, {}, 0, {}, {}, {}};
  progress::report("marching cubes: inside", 0.0);
  run.classify_points();
  run.count_rows();
  std::vector<std::uint64_t> keys = run.soup();
  progress::report("marching cubes: weld", 0.5);
  run.weld(std::move(keys));
  progress::report("marching cubes: number points", 0.6);
  ClassicMarchingCubes out;
  run.points(out);
  run.faces(out);
  progress::report("marching cubes", 1.0);
  return out;
}

}  // namespace keymesh::generate
