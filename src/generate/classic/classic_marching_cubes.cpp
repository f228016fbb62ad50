#include "keymesh/generate/classic/classic_marching_cubes.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <optional>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/core/free_storage.hpp"
#include "keymesh/core/progress.hpp"
#include "keymesh/generate/contour/marching_cubes_table.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/scan.hpp"
#include "generate/contour/history_t.hpp"

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

// ---- Marching Cubes 33 (Lewiner et al. 2003), the decisions ----
//
// The tables (Mc33Tables) say, for each of the 256 cases, which of the
// 15 configurations it is (CASES: case number, configuration index), which
// cube faces decide an ambiguous configuration (TESTn: face ids, signed),
// and the triangles of each resolution (TILINGn: edge ids, 12 = the centre).
// What follows picks the resolution from the corner values, with the
// arithmetic scikit-image uses (its results are matched bit for bit).

// A table row: data + (config * subs + sub) * len.
struct Mc33Lut {
  const std::int8_t* data = nullptr;
  int rows = 0, subs = 1, len = 0;
  const std::int8_t* row(int config, int sub = 0) const {
    return data + (static_cast<std::size_t>(config) * static_cast<std::size_t>(subs) + static_cast<std::size_t>(sub)) *
                      static_cast<std::size_t>(len);
  }
  int at(int config, int k) const { return row(config)[k]; }
  int triangles() const { return len / 3; }
};

// Cube face f (1..6) as its corners A B C D: the four sides (k = 0..3: from
// bottom corner k up, across to k + 1 and down), then bottom and top.
constexpr int kFace[6][4] = {{0, 4, 5, 1}, {1, 5, 6, 2}, {2, 6, 7, 3}, {3, 7, 4, 0}, {0, 3, 2, 1}, {4, 7, 6, 5}};

int corner_at(int x, int y, int z) {
  for (int k = 0; k < 8; ++k)
    if (kCorner[k][0] == x && kCorner[k][1] == y && kCorner[k][2] == z) return k;
  return -1;
}

// For the interior test along classic edge e: the edge and its three
// parallels, each as (start, end) corners with the same direction. B starts
// at the ring neighbour before e's start on its level; D at the corner
// above/below e's start for a level edge, at the ring neighbour after it for
// an upright edge; C across from e's start.
struct ParallelEdges {
  int start[4], end[4];
};

ParallelEdges parallel_edges(int e) {
  ParallelEdges p{};
  const int s = kEdge[e][0], t = kEdge[e][1];
  const int level = s / 4 * 4, ring = s % 4;
  const int b = level + (ring + 3) % 4;
  const int d = e < 8 ? (s ^ 4) : level + (ring + 1) % 4;
  const int c = corner_at(kCorner[b][0] + kCorner[d][0] - kCorner[s][0], kCorner[b][1] + kCorner[d][1] - kCorner[s][1],
                          kCorner[b][2] + kCorner[d][2] - kCorner[s][2]);
  const int from[4] = {s, b, c, d};
  for (int i = 0; i < 4; ++i) {
    p.start[i] = from[i];
    p.end[i] = corner_at(kCorner[from[i]][0] + kCorner[t][0] - kCorner[s][0],
                         kCorner[from[i]][1] + kCorner[t][1] - kCorner[s][1],
                         kCorner[from[i]][2] + kCorner[t][2] - kCorner[s][2]);
  }
  return p;
}

class Mc33 {
 public:
  explicit Mc33(const Mc33Tables& t) {
    cases_ = lut(t, "CASES", 2, 256);
    subconfig13_ = lut(t, "SUBCONFIG13", 1, 64);
    for (int i = 0; i < kTables; ++i) tables_[i] = lut(t, kNames[i], i < kFirstTiling ? 1 : 2, 0);
    for (int e = 0; e < 12; ++e) parallel_[e] = parallel_edges(e);
    validate();
    // Cases without a test: their triangles once, for a lookup per cube.
    for (int index = 0; index < 256; ++index) {
      fixed_count_[index] = -1;
      const auto no_values = [](double* v) { std::fill(v, v + 8, 0.0); };  // not read for these cases
      switch (cases_.at(index, 0)) {
        case 0: case 1: case 2: case 5: case 8: case 9: case 11: case 14:
          fixed_count_[index] = tiling_of(index, no_values, fixed_edges_[index]);
          break;
        default: break;
      }
    }
  }

  // The triangles of a cube of case `index` (classic corner bits): their
  // count, `edges` pointed at 3 * count edge ids. `values(v)` fills the
  // eight corner values minus the level; called only for ambiguous cases.
  template <class Values>
  int tiling(int index, Values&& values, const std::int8_t*& edges) const {
    if (fixed_count_[index] >= 0) {
      edges = fixed_edges_[index];
      return fixed_count_[index];
    }
    return tiling_of(index, values, edges);
  }

 private:
  template <class Values>
  int tiling_of(int index, Values&& values, const std::int8_t*& edges) const {
    const int kase = cases_.at(index, 0), config = cases_.at(index, 1);
    const auto use = [&](int table, int sub = 0) {
      edges = tables_[table].row(config, sub);
      return tables_[table].triangles();
    };
    double v[8];
    switch (kase) {
      case 1: return use(T1);
      case 2: return use(T2);
      case 5: return use(T5);
      case 8: return use(T8);
      case 9: return use(T9);
      case 11: return use(T11);
      case 14: return use(T14);
      case 3:
        values(v);
        return use(face(v, tables_[TEST3].at(config, 0)) ? T3_2 : T3_1);
      case 4:
        values(v);
        return use(interior(v, -1, tables_[TEST4].at(config, 0)) ? T4_1 : T4_2);
      case 6: {
        values(v);
        const Mc33Lut& test = tables_[TEST6];
        if (face(v, test.at(config, 0))) return use(T6_2);
        return use(interior(v, test.at(config, 2), test.at(config, 1)) ? T6_1_1 : T6_1_2);
      }
      case 7: {
        values(v);
        const Mc33Lut& test = tables_[TEST7];
        const int bits = face_bits(v, test, config, 3);
        switch (bits) {
          case 0: return use(T7_1);
          case 1: case 2: case 4: return use(T7_2, bits >> 1);            // the face that separates
          case 3: case 5: case 6: return use(T7_3, (bits ^ 7) == 4 ? 0 : (bits ^ 7) == 2 ? 1 : 2);
          default: return use(interior(v, test.at(config, 4), test.at(config, 3)) ? T7_4_2 : T7_4_1);
        }
      }
      case 10:
      case 12: {
        values(v);
        const bool ten = kase == 10;
        const Mc33Lut& test = tables_[ten ? TEST10 : TEST12];
        const bool first = face(v, test.at(config, 0)), second = face(v, test.at(config, 1));
        if (first && second) return use(ten ? T10_1_1_ : T12_1_1_);
        if (first) return use(ten ? T10_2 : T12_2);
        if (second) return use(ten ? T10_2_ : T12_2_);
        const bool joined = interior(v, ten ? -1 : test.at(config, 3), test.at(config, 2));
        return use(ten ? (joined ? T10_1_1 : T10_1_2) : (joined ? T12_1_1 : T12_1_2));
      }
      case 13: {
        values(v);
        const Mc33Lut& test = tables_[TEST13];
        const int sub = subconfig13_.at(face_bits(v, test, config, 6), 0);
        if (sub == 0) return use(T13_1);
        if (sub <= 6) return use(T13_2, sub - 1);
        if (sub <= 18) return use(T13_3, sub - 7);
        if (sub <= 22) return use(T13_4, sub - 19);
        if (sub <= 26) {
          const int edge = tables_[T13_5_1].row(config, sub - 23)[0];
          return use(interior(v, edge, test.at(config, 6)) ? T13_5_1 : T13_5_2, sub - 23);
        }
        if (sub <= 38) return use(T13_3_, sub - 27);
        if (sub <= 44) return use(T13_2_, sub - 39);
        if (sub == 45) return use(T13_1_);
        return 0;  // SUBCONFIG13's -1: no such configuration
      }
      default: return 0;
    }
  }

  enum {
    TEST3, TEST4, TEST6, TEST7, TEST10, TEST12, TEST13,
    T1, T2, T3_1, T3_2, T4_1, T4_2, T5, T6_1_1, T6_1_2, T6_2, T7_1, T7_2, T7_3, T7_4_1, T7_4_2, T8, T9,
    T10_1_1, T10_1_1_, T10_1_2, T10_2, T10_2_, T11, T12_1_1, T12_1_1_, T12_1_2, T12_2, T12_2_,
    T13_1, T13_1_, T13_2, T13_2_, T13_3, T13_3_, T13_4, T13_5_1, T13_5_2, T14, kTables
  };
  static constexpr int kFirstTiling = T1;
  static constexpr const char* kNames[kTables] = {
      "TEST3", "TEST4", "TEST6", "TEST7", "TEST10", "TEST12", "TEST13",
      "TILING1", "TILING2", "TILING3_1", "TILING3_2", "TILING4_1", "TILING4_2", "TILING5", "TILING6_1_1",
      "TILING6_1_2", "TILING6_2", "TILING7_1", "TILING7_2", "TILING7_3", "TILING7_4_1", "TILING7_4_2", "TILING8",
      "TILING9", "TILING10_1_1", "TILING10_1_1_", "TILING10_1_2", "TILING10_2", "TILING10_2_", "TILING11",
      "TILING12_1_1", "TILING12_1_1_", "TILING12_1_2", "TILING12_2", "TILING12_2_", "TILING13_1", "TILING13_1_",
      "TILING13_2", "TILING13_2_", "TILING13_3", "TILING13_3_", "TILING13_4", "TILING13_5_1", "TILING13_5_2",
      "TILING14"};

  static Mc33Lut lut(const Mc33Tables& t, const char* name, int min_dims, int rows) {
    const auto it = t.find(name);
    if (it == t.end()) throw InputError(std::string("marching cubes 33: table ") + name + " is missing");
    const Mc33Array& a = it->second;
    std::size_t size = 1;
    for (int n : a.shape) size *= static_cast<std::size_t>(std::max(n, 0));
    if (a.shape.size() < static_cast<std::size_t>(min_dims) || a.shape.size() > 3 || size != a.data.size() ||
        size == 0 || (rows > 0 && a.shape[0] != rows))
      throw InputError(std::string("marching cubes 33: table ") + name + " has an unexpected shape");
    Mc33Lut l;
    l.data = a.data.data();
    l.rows = a.shape[0];
    l.subs = a.shape.size() == 3 ? a.shape[1] : 1;
    l.len = a.shape.size() == 1 ? 1 : a.shape.back();
    return l;
  }

  // Every row a case can reach exists and holds edge ids 0..12, face ids
  // 1..6 (signed) and test edges 0..11: what tiling() reads stays inside.
  void validate() const {
    const auto fail = [](const char* what) {
      throw InputError(std::string("marching cubes 33: tables out of range (") + what + ")");
    };
    for (int t = kFirstTiling; t < kTables; ++t) {
      const Mc33Lut& l = tables_[t];
      if (l.len % 3 != 0 || l.len == 0) fail(kNames[t]);
      for (std::size_t i = 0; i < static_cast<std::size_t>(l.rows) * l.subs * l.len; ++i)
        if (l.data[i] < 0 || l.data[i] > 12) fail(kNames[t]);
    }
    // TEST3 TEST4 TEST6 TEST7 TEST10 TEST12 TEST13: face ids first, then
    // the interior test's sign and edge where there is one.
    const int faces[7] = {1, 0, 1, 3, 2, 2, 6}, widths[7] = {1, 1, 3, 5, 3, 4, 7};
    for (int i = 0; i < 7; ++i) {
      const Mc33Lut& l = tables_[TEST3 + i];
      if (l.len < widths[i]) fail(kNames[TEST3 + i]);
      for (int r = 0; r < l.rows; ++r)
        for (int k = 0; k < faces[i]; ++k)
          if (std::abs(l.at(r, k)) < 1 || std::abs(l.at(r, k)) > 6) fail(kNames[TEST3 + i]);
    }
    const auto edge_ok = [&](const Mc33Lut& l, int k) {
      for (int r = 0; r < l.rows; ++r)
        if (l.at(r, k) < 0 || l.at(r, k) > 11) fail("interior test edge");
    };
    edge_ok(tables_[TEST6], 2);
    edge_ok(tables_[TEST7], 4);
    edge_ok(tables_[TEST12], 3);
    if (tables_[T7_2].subs < 3 || tables_[T7_3].subs < 3 || tables_[T13_2].subs < 6 || tables_[T13_2_].subs < 6 ||
        tables_[T13_3].subs < 12 || tables_[T13_3_].subs < 12 || tables_[T13_4].subs < 4 ||
        tables_[T13_5_1].subs < 4 || tables_[T13_5_2].subs < 4)
      fail("sub-configurations");
    for (int r = 0; r < tables_[T13_5_1].rows * 4; ++r)
      if (tables_[T13_5_1].data[static_cast<std::size_t>(r) * tables_[T13_5_1].len] > 11) fail("case 13.5 edge");
    for (int s = 0; s < 64; ++s)
      if (subconfig13_.at(s, 0) < -1 || subconfig13_.at(s, 0) > 45) fail("SUBCONFIG13");
    // The configuration of every case within each table the case reads.
    const std::vector<std::vector<int>> reads = {
        {}, {T1}, {T2}, {T3_1, T3_2, TEST3}, {T4_1, T4_2, TEST4}, {T5}, {T6_1_1, T6_1_2, T6_2, TEST6},
        {T7_1, T7_2, T7_3, T7_4_1, T7_4_2, TEST7}, {T8}, {T9},
        {T10_1_1, T10_1_1_, T10_1_2, T10_2, T10_2_, TEST10}, {T11},
        {T12_1_1, T12_1_1_, T12_1_2, T12_2, T12_2_, TEST12},
        {T13_1, T13_1_, T13_2, T13_2_, T13_3, T13_3_, T13_4, T13_5_1, T13_5_2, TEST13}, {T14}};
    for (int index = 0; index < 256; ++index) {
      const int kase = cases_.at(index, 0), config = cases_.at(index, 1);
      if (kase < 0 || kase > 14) fail("CASES");
      for (int t : reads[static_cast<std::size_t>(kase)])
        if (config < 0 || config >= tables_[t].rows) fail("CASES configuration");
    }
  }

  // Bit i set when face test i of `config`'s row passes (i < n).
  int face_bits(const double v[8], const Mc33Lut& test, int config, int n) const {
    int bits = 0;
    for (int i = 0; i < n; ++i)
      if (face(v, test.at(config, i))) bits |= 1 << i;
    return bits;
  }

  // Whether the surface joins the two inside corners across cube face
  // |f| (the asymptotic decider: the sign of A*C - B*D, taken relative to
  // corner A and to f's sign; a decider within eps of zero says f >= 0).
  static bool face(const double v[8], int f) {
    const int* q = kFace[std::abs(f) - 1];
    const double a = v[q[0]], b = v[q[1]], c = v[q[2]], d = v[q[3]];
    const double decider = a * c - b * d;
    if (decider > -kEpsilon && decider < kEpsilon) return f >= 0;
    return static_cast<double>(f) * a * decider >= 0;
  }

  // The interior test: the values on the four parallel edges at the height
  // t where the bilinear section is most ambiguous (cases 4 and 10: along z,
  // t from the quadratic's vertex; otherwise at the crossing on `edge`),
  // and whether the section there joins the ends that `s`'s sign names.
  bool interior(const double v[8], int edge, int s) const {
    double at, bt, ct, dt;
    if (edge < 0) {
      const double a = (v[4] - v[0]) * (v[6] - v[2]) - (v[7] - v[3]) * (v[5] - v[1]);
      const double b = v[2] * (v[4] - v[0]) + v[0] * (v[6] - v[2]) - v[1] * (v[7] - v[3]) - v[3] * (v[5] - v[1]);
      const double t = -b / (2 * a + kEpsilon);
      if (t < 0 || t > 1) return s > 0;
      at = v[0] + (v[4] - v[0]) * t;
      bt = v[3] + (v[7] - v[3]) * t;
      ct = v[2] + (v[6] - v[2]) * t;
      dt = v[1] + (v[5] - v[1]) * t;
    } else {
      const ParallelEdges& p = parallel_[edge];
      const double t = v[p.start[0]] / (v[p.start[0]] - v[p.end[0]] + kEpsilon);
      const auto along = [&](int i) { return v[p.start[i]] + (v[p.end[i]] - v[p.start[i]]) * t; };
      at = 0;
      bt = along(1);
      ct = along(2);
      dt = along(3);
    }
    const int above = (at >= 0 ? 1 : 0) | (bt >= 0 ? 2 : 0) | (ct >= 0 ? 4 : 0) | (dt >= 0 ? 8 : 0);
    const int count = (above & 1) + (above >> 1 & 1) + (above >> 2 & 1) + (above >> 3 & 1);
    if (count >= 3) return s < 0;
    // Two opposite ends: the face-like decider of the section. scikit-image
    // answers false (not s < 0) when it does not hold; kept.
    if (above == 5) return at * ct - bt * dt < kEpsilon ? s > 0 : false;
    if (above == 10) return at * ct - bt * dt >= kEpsilon ? s > 0 : false;
    return s > 0;
  }

  Mc33Lut cases_, subconfig13_;
  int fixed_count_[256];
  const std::int8_t* fixed_edges_[256] = {};
  Mc33Lut tables_[kTables];
  ParallelEdges parallel_[12];
};

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
  const Mc33* mc33;                        // set: Lewiner's method, else the classic table
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
  Id cubes() const { return g.cx * g.cy * g.cz; }
  // Keys: 3 per coarse point (its edges along x, y, z), then one per cube
  // (its centre point, Marching Cubes 33 only).
  std::uint64_t centre_keys() const { return 3 * static_cast<std::uint64_t>(g.px * g.py * g.pz); }

  // Marching Cubes 33: cube (X, Y, Z)'s triangles (count; `edges` at their
  // edge ids) from its case and, where ambiguous, its values.
  int mc33_tiling(Id X, Id Y, Id Z, const std::int8_t*& edges) const {
    return mc33->tiling(cube_case(above, g, X, Y, Z), [&](double v[8]) {
      cube_values(volume, g, level, X * g.step, Y * g.step, Z * g.step, v);
    }, edges);
  }

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
        const std::int8_t* edges = nullptr;
        n += static_cast<std::uint64_t>(mc33 ? mc33_tiling(X, Y, Z, edges)
                                             : triangles_of_case[cube_case(above, g, X, Y, Z)]);
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
        const std::int8_t* row = nullptr;
        int n = 0;
        if (mc33) {
          n = 3 * mc33_tiling(X, Y, Z, row);
        } else {
          row = table[cube_case(above, g, X, Y, Z)].data();
          while (n < 15 && row[n - n % 3] >= 0) ++n;
        }
        const std::uint64_t cube = static_cast<std::uint64_t>((Z * g.cy + Y) * g.cx + X);
        for (int k = 0; k < n; ++k) {
          const int e = row[k];
          if (e == 12) {
            keys[at] = centre_keys() + cube;
          } else {
            const int a = kEdge[e][0], b = kEdge[e][1];
            const int lo = kCorner[a][edge_axis(e)] == 0 ? a : b;
            keys[at] = g.edge_key(X + kCorner[lo][0], Y + kCorner[lo][1], Z + kCorner[lo][2], edge_axis(e));
          }
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
    const std::uint64_t key_range = centre_keys() + (mc33 ? static_cast<std::uint64_t>(cubes()) : 0);
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

  // Point p's history (ClassicMarchingCubes::history_key): its key in the
  // array's frame and the float t that gives its vertex along the edge back.
  void history(Id p, const double xyz[3], std::uint64_t& key_out, float& t_out) const {
    const std::uint64_t key = groups.unique_keys[p];
    const std::uint64_t n0 = static_cast<std::uint64_t>(g.n0), n1 = static_cast<std::uint64_t>(g.n1);
    const bool centre_point = key >= centre_keys();
    const Id c = static_cast<Id>(centre_point ? key - centre_keys() : key / 3);
    // Coarse (X, Y, Z), x fastest, over cubes (centres) or coarse points (edges).
    const Id nx = centre_point ? g.cx : g.px, ny = centre_point ? g.cy : g.py;
    const Id X = c % nx, Y = (c / nx) % ny, Z = c / (nx * ny);
    const std::uint64_t at = static_cast<std::uint64_t>(Z * g.step) +
                             n0 * (static_cast<std::uint64_t>(Y * g.step) + n1 * static_cast<std::uint64_t>(X * g.step));
    if (centre_point) {
      key_out = 3 * n0 * n1 * static_cast<std::uint64_t>(g.n2) + at;
      t_out = 0.5f;
      return;
    }
    const int axis = static_cast<int>(key % 3);  // 0 = x = array axis 2
    key_out = 3 * at + static_cast<std::uint64_t>(2 - axis);
    const double lo = static_cast<double>((axis == 0 ? X : axis == 1 ? Y : Z) * g.step);
    const double step = static_cast<double>(g.step);
    const float written = static_cast<float>(xyz[axis]);
    const double t = (xyz[axis] - lo) / step;
    t_out = nearest_float_t(t, [&](float f) { return static_cast<float>(lo + step * static_cast<double>(f)) == written; });
  }

  // Position of point p's edge crossing (x, y, z): scikit-image's base +
  // step * f / ff with ff the weight sum and f the far corner's weight along
  // the edge (the cross axes are whole numbers).
  void crossing(Id p, double xyz[3]) const {
    const std::uint64_t key = groups.unique_keys[p];
    if (key >= centre_keys()) {
      centre(static_cast<Id>(key - centre_keys()), xyz, nullptr, nullptr, nullptr);
      return;
    }
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

  // The centre point of cube `cube` (Marching Cubes 33): every corner's
  // weight 1 / (eps + |v - level|), the position their centre of mass (sums
  // in corner order, as scikit-image) and, with g_low/g_high, the gradient
  // the weighted sum of the corners' one-sided differences.
  void centre(Id cube, double xyz[3], const int (*g_low)[3], const int (*g_high)[3], double gradient[3]) const {
    const Id X = cube % g.cx, Y = (cube / g.cx) % g.cy, Z = cube / (g.cx * g.cy);
    double v[8], w[8];
    cube_values(volume, g, level, X * g.step, Y * g.step, Z * g.step, v);
    for (int k = 0; k < 8; ++k) w[k] = corner_weight(v[k]);
    if (xyz) {
      double f[3] = {0, 0, 0}, ff = 0;
      for (int k = 0; k < 8; ++k) {
        for (int a = 0; a < 3; ++a) f[a] += static_cast<double>(kCorner[k][a]) * w[k];
        ff += w[k];
      }
      const Id base[3] = {X * g.step, Y * g.step, Z * g.step};
      for (int a = 0; a < 3; ++a)
        xyz[a] = static_cast<double>(base[a]) + static_cast<double>(g.step) * f[a] / ff;
    }
    if (gradient)
      for (int a = 0; a < 3; ++a) {
        gradient[a] = w[0] * (v[g_low[0][a]] - v[g_high[0][a]]);
        for (int k = 1; k < 8; ++k) gradient[a] += w[k] * (v[g_low[k][a]] - v[g_high[k][a]]);
      }
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
      if (e == 12) {
        double gradient[3];
        centre(cube, nullptr, g_low, g_high, gradient);
        for (int a = 0; a < 3; ++a) n[a] += static_cast<float>(gradient[a]);
        continue;
      }
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
    if (o.history) {
      out.history_key.resize(static_cast<std::size_t>(points));
      out.history_t.resize(static_cast<std::size_t>(points));
    }
    for_each_reporting(points, "marching cubes: points", 0.7, 0.95, 256, [&](Id p) {
      double xyz[3];
      crossing(p, xyz);
      if (o.history) {
        const std::size_t at = static_cast<std::size_t>(point_id[p]);
        history(p, xyz, out.history_key[at], out.history_t[at]);
      }
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
  std::optional<Mc33> mc33;
  if (o.mc33) mc33.emplace(*o.mc33);
  ClassicRun run{volume, table, o, mc33 ? &*mc33 : nullptr, g, o.level, {}, {}, 0, {}, {}, {}};
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
