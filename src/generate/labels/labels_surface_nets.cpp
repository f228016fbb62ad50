// Surface nets on a label map (see keymesh/generate/labels/labels.hpp): the map step
// writes, for every grid edge whose end labels differ, a quad of four cell
// keys (the cells around the edge) and the edge's label pair; KEY-REDUCE's
// dense plan turns the keys into points (one per cell met) and the index map
// into the triangle list. Quads are written in grid order, so the output
// depends on the volume alone (any thread count gives the same bits).
#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <limits>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/generate/contour/marching_cubes_table.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"
#include "keymesh/generate/labels/label_kernels.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The loops a cell's label boundary makes on the cell's faces: the polygons
// of the marching cubes case table (generate/marching_cubes_table.hpp, whose
// face rule keeps the label's corners apart across a face diagonal). The
// cube edges one polygon cuts form one loop; a cell gets one point per loop,
// so a per-label surface is the dual of the label's marching cubes surface
// and a closed 2-manifold like it (one point per cell would pinch where
// voxels meet along an edge or a corner, or where a tunnel crosses a cell).
struct CellLoops {
  std::array<std::array<std::uint8_t, 12>, 256> loop_of;  // loop of each cut cube edge
  std::array<std::uint8_t, 256> loops;
  std::array<std::array<std::uint8_t, 3>, 8> edge_at;  // cube edge from corner c along axis a
};

const CellLoops& cell_loops() {
  static const CellLoops table = [] {
    const auto& mc = marching_cubes_table();
    CellLoops t{};
    for (int e = 0; e < 12; ++e) t.edge_at[mc.edges[e].corner0][mc.edges[e].axis] = static_cast<std::uint8_t>(e);
    for (int c = 0; c < 256; ++c) {
      // Union-find over the cube edges of each triangle: a polygon's fan.
      std::array<int, 12> parent;
      for (int e = 0; e < 12; ++e) parent[e] = e;
      auto find = [&](int e) {
        while (parent[e] != e) e = parent[e] = parent[parent[e]];
        return e;
      };
      std::array<bool, 12> cut{};
      for (int k = 0; k < 3 * mc.triangle_count[c]; ++k) cut[mc.triangle_edges[c][k]] = true;
      for (int tri = 0; tri < mc.triangle_count[c]; ++tri) {
        const auto* e = &mc.triangle_edges[c][3 * tri];
        parent[find(e[1])] = find(e[0]);
        parent[find(e[2])] = find(e[0]);
      }
      std::array<int, 12> id;
      id.fill(-1);
      int next = 0;
      for (int e = 0; e < 12; ++e) {
        if (!cut[e]) continue;
        const int r = find(e);
        if (id[r] < 0) id[r] = next++;
        t.loop_of[c][e] = static_cast<std::uint8_t>(id[r]);
      }
      t.loops[c] = static_cast<std::uint8_t>(next);
    }
    return t;
  }();
  return table;
}

// A box of the padded grid: points [lo, lo + dims) per axis. The cells of
// the box are the cubes between its points.
struct Box {
  std::array<Id, 3> lo{}, dims{};
  Id cx() const { return dims[0] - 1; }
  Id cxy() const { return (dims[0] - 1) * (dims[1] - 1); }
  Id cells() const { return cxy() * (dims[2] - 1); }
};

// Everything one run of the generator writes, before welding. Arrays: sized
// without a fill, as every element is written.
template <class K>
struct Soup {
  Array<K> keys;                // 3 per triangle (a quad: (C00, C10, C11), (C00, C11, C01))
  Array<std::uint32_t> pair;    // per triangle: first << 16 | second
};

// Labels of the 8 corners of the cell whose first corner is padded point p.
struct CellCorners {
  const LabelVolume& v;
  std::array<Id, 8> offset;
  explicit CellCorners(const LabelVolume& vol) : v(vol) {
    for (int c = 0; c < 8; ++c) offset[c] = (c & 1) + ((c >> 1) & 1) * vol.dims[0] + ((c >> 2) & 1) * vol.nxy;
  }
  std::array<LabelIndex, 8> labels(Id p) const {
    std::array<LabelIndex, 8> out;
    for (int c = 0; c < 8; ++c) out[c] = v.label(p + offset[c]);
    return out;
  }
  static unsigned case_of(const std::array<LabelIndex, 8>& corner, LabelIndex l) {
    unsigned m = 0;
    for (int c = 0; c < 8; ++c) m |= static_cast<unsigned>(corner[c] == l) << c;
    return m;
  }
  static int distinct(const std::array<LabelIndex, 8>& corner) {
    return label_kernels::distinct_corner_labels([&](int c) { return corner[c]; });
  }
};

// Face points (per-label surface nets only) are keyed after the cell
// points: 4 * cells + 2 * (3 * cell + normal axis) + arc, the face named by
// the cell of its lower corner.
constexpr Id kFaceKeysPerCell = 6;

// The map step over the edges of `box` (every edge between two of its
// points). With `only` < 0: every edge whose labels differ, keyed by cell
// (network); otherwise only edges with exactly one end of label `only`,
// keyed by 4 * cell + loop (that label's closed surface).
//
// Per label, a quad side between two cells is split by a face point where
// the pinch of labels.hpp would occur: the shared face is ambiguous (the
// label on one diagonal) and in both cells its two arcs belong to one loop,
// so that the quads of the face's four edges would all meet on one dual
// edge. The face point of the arc (around the label's corner of this edge)
// takes the side instead; the polygon is fanned from its first face point.
//
// Only the edges of rows k in [rows.first, rows.second) of the box (its
// z-planes, box coordinates) are visited: a slab of a streamed volume.
template <class K>
class EdgePolygons {
 public:
  EdgePolygons(const LabelVolume& vol, const Box& box, int only, std::pair<Id, Id> krange)
      : vol_(vol), box_(box), only_(only), krange_(krange), loops_(cell_loops()),
        cstride_{1, box.cx(), box.cxy()}, pstride_{1, vol.dims[0], vol.nxy}, cells_(box.cells()) {
    for (int axis = 0; axis < 3; ++axis) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int da = 0; da < 2; ++da)
        for (int dv = -1; dv <= 1; ++dv)
          for (int du = -1; du <= 1; ++du)
            around_[axis][around_bit(da, du, dv)] = da * pstride_[axis] + du * pstride_[u] + dv * pstride_[v];
      for (unsigned g = 0; g < 256; ++g) {
        unsigned cube = 0;
        for (int c = 0; c < 8; ++c) cube |= ((g >> (((c >> u) & 1) + 2 * ((c >> v) & 1) + 4 * ((c >> axis) & 1))) & 1u) << c;
        case_of_[axis][g] = static_cast<std::uint8_t>(cube);
      }
      // A face's corners relative to p: its lower corner (face_between at
      // p = 0) plus oa along axis and ow along w.
      const Id origin[3] = {0, 0, 0};
      for (int m = 0; m < 4; ++m) {
        const Face face = face_between(origin, axis, m);
        for (int corner = 0; corner < 4; ++corner) {
          Id q[3] = {face.f[0], face.f[1], face.f[2]};
          q[axis] += corner & 1, q[face.w] += corner >> 1;
          face_bit_[axis][m][corner] =
              static_cast<std::uint8_t>(around_bit(static_cast<int>(q[axis]), static_cast<int>(q[u]), static_cast<int>(q[v])));
        }
      }
    }
  }

  // Rows of the box the edges are visited in (y fastest, then z).
  Id rows() const { return box_.dims[1] * (krange_.second - krange_.first); }

  // Visits the edges of row r whose polygons are written:
  // f(i, j, k, axis, lo_end_label, hi_end_label), in box coordinates.
  // Runs of kRun points that start no such edge are stepped over at once
  // (quiet_run); the others visited one by one, in the same order.
  template <class F>
  void visit_row(Id r, F&& f) const {
    const Id j = r % box_.dims[1], k = krange_.first + r / box_.dims[1];
    const Id row_first = vol_.at(box_.lo[0], box_.lo[1] + j, box_.lo[2] + k);
    const bool y_ok = j + 1 < box_.dims[1], z_ok = k + 1 < box_.dims[2];
    const LabelIndex* row = vol_.row(row_first);
    const LabelIndex* y_row = y_ok ? row + pstride_[1] : row;  // no edge along y or z: the row itself
    const LabelIndex* z_row = z_ok ? row + pstride_[2] : row;
    for (Id i = 0; i < box_.dims[0]; ++i) {
      if (i % kRun == 0 && i + kRun < box_.dims[0] && quiet_run(row + i, y_row + i, z_row + i)) {
        i += kRun - 1;
        continue;
      }
      const Id p = row_first + i;
      const LabelIndex a = label(p);
      const LabelIndex ends[3] = {i + 1 < box_.dims[0] ? label(p + 1) : a, y_ok ? label(p + pstride_[1]) : a,
                                  z_ok ? label(p + pstride_[2]) : a};
      for (int axis = 0; axis < 3; ++axis) {
        const LabelIndex b = ends[axis];
        if (a == b) continue;
        if (only_ >= 0 && a != only_ && b != only_) continue;
        f(i, j, k, axis, a, b);
      }
    }
  }

  // The polygon of one edge: its corner keys counter-clockwise seen from
  // +axis (cells, with face points between some), written to `out` when
  // given; returns the number of corners.
  int polygon(Id i, Id j, Id k, int axis, LabelIndex a, K* out) const {
    if (only_ >= 0) return label_polygon(i, j, k, axis, a, out);
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const Id cell = i + j * cstride_[1] + k * cstride_[2];  // the cell whose first corner is p
    if (out)
      for (int m = 0; m < 4; ++m)
        out[m] = static_cast<K>(cell - kAround[m][0] * cstride_[u] - kAround[m][1] * cstride_[v]);
    return 4;
  }

  // The network's quad of the edge from label a to label b (label_kernels::
  // network_quad, the device path's too) as triangles t and t + 1.
  void write_network_quad(Id i, Id j, Id k, int axis, LabelIndex a, LabelIndex b, Id t, Soup<K>& soup) const {
    label_kernels::network_quad(i + j * cstride_[1] + k * cstride_[2], cstride_, axis, a < b, soup.keys.data() + 3 * t);
    const LabelIndex lo = a < b ? a : b, hi = a < b ? b : a;
    soup.pair[static_cast<std::size_t>(t)] = soup.pair[static_cast<std::size_t>(t + 1)] = (std::uint32_t{lo} << 16) | hi;
  }

  // Writes the triangles of the polygon of the edge from label a to label b
  // (n corners) at triangle t, with their label pair.
  void write_fan(K* poly, int n, LabelIndex a, LabelIndex b, Id t, Soup<K>& soup) const {
    // Normal +axis points from a to b: keep the order when a is the
    // smaller label (network) or the surface's label (per label).
    if (!(only_ < 0 ? a < b : a == only_)) std::reverse(poly + 1, poly + n);
    // Fan from the first face point (corners that are face keys), else
    // the quad's two triangles (C00, C10, C11), (C00, C11, C01).
    int apex = 0;
    for (int m = 0; m < n; ++m)
      if (static_cast<Id>(poly[m]) >= 4 * cells_ && only_ >= 0) {
        apex = m;
        break;
      }
    K* o = soup.keys.data() + 3 * t;
    for (int m = 1; m + 1 < n; ++m) {
      *o++ = poly[apex];
      *o++ = poly[(apex + m) % n];
      *o++ = poly[(apex + m + 1) % n];
    }
    const LabelIndex lo = a < b ? a : b, hi = a < b ? b : a;
    for (int m = 0; m < n - 2; ++m) soup.pair[static_cast<std::size_t>(t + m)] = (std::uint32_t{lo} << 16) | hi;
  }

 private:
  // The four cells around an edge along `axis`, as offsets along the next
  // two axes (u, v), counter-clockwise seen from +axis.
  static constexpr int kAround[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};

  // The face between cells m and m + 1 of an edge: its normal axis d, the
  // axis w it spans besides the edge's, and its lower corner f (box
  // coordinates).
  struct Face {
    int d, w;
    Id f[3];
  };

  LabelIndex label(Id p) const { return vol_.label(p); }

  // Whether none of the kRun points from `row` on starts an edge visit_row
  // visits (the row needs kRun + 1 points): with `only`, each has that
  // label exactly when its ends along x, y, z have it (outside the label
  // or inside it); else each equals its three ends. Eight labels a
  // comparison (GCC vector extensions: SSE2 lanes on x86-64, plain code
  // elsewhere).
  static constexpr Id kRun = 8;
  bool quiet_run(const LabelIndex* row, const LabelIndex* y_row, const LabelIndex* z_row) const {
    using Lanes = LabelIndex __attribute__((vector_size(kRun * sizeof(LabelIndex))));
    Lanes a, x, y, z;
    std::memcpy(&a, row, sizeof a);
    std::memcpy(&x, row + 1, sizeof x);
    std::memcpy(&y, y_row, sizeof y);
    std::memcpy(&z, z_row, sizeof z);
    const Lanes l = Lanes{} + static_cast<LabelIndex>(only_);
    const auto in = a == l;
    const auto hit = only_ >= 0 ? (in != (x == l)) | (in != (y == l)) | (in != (z == l))
                                : (a != x) | (a != y) | (a != z);
    std::uint64_t words[sizeof hit / sizeof(std::uint64_t)];
    std::memcpy(words, &hit, sizeof hit);
    std::uint64_t any = 0;
    for (std::uint64_t w : words) any |= w;
    return any == 0;
  }

  // The polygon of an edge of label `only`'s surface: the loop keys of the
  // four cells around it, with a face point after cell m where the face to
  // cell m + 1 would pinch.
  int label_polygon(Id i, Id j, Id k, int axis, LabelIndex a, K* out) const {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const Id cell = i + j * cstride_[1] + k * cstride_[2];
    const Id lp[3] = {i, j, k};  // p in box coordinates
    // The 18 labels of the four cells, read once: the cells' cases and
    // their faces' corners are bits of them.
    const std::uint32_t near = around(vol_.at(box_.lo[0] + i, box_.lo[1] + j, box_.lo[2] + k), axis);
    unsigned cube[4];
    for (int m = 0; m < 4; ++m) cube[m] = cell_case(near, axis, m);
    int n = 0;
    for (int m = 0; m < 4; ++m) {
      const int corner0 = (kAround[m][0] << u) | (kAround[m][1] << v);
      if (out)
        out[n] = static_cast<K>(4 * (cell - kAround[m][0] * cstride_[u] - kAround[m][1] * cstride_[v]) +
                                loops_.loop_of[cube[m]][loops_.edge_at[corner0][axis]]);
      ++n;
      if (!ambiguous(near, axis, m)) continue;
      const Id face_key = face_point(lp, face_between(lp, axis, m), axis, a == only_ ? 0 : 1, m, cube);
      if (face_key < 0) continue;
      if (out) out[n] = static_cast<K>(face_key);
      ++n;
    }
    return n;
  }

  Face face_between(const Id lp[3], int axis, int m) const {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const int m1 = (m + 1) % 4;
    Face face{};
    face.d = kAround[m][0] != kAround[m1][0] ? u : v;
    face.w = face.d == u ? v : u;  // the face spans axis and w
    const int fs[2] = {std::min(kAround[m][0], kAround[m1][0]), std::min(kAround[m][1], kAround[m1][1])};
    // Lower corner: p minus the cells' shared offsets.
    for (int x = 0; x < 3; ++x) face.f[x] = lp[x];
    face.f[u] -= (face.d == u ? 0 : fs[0]);
    face.f[v] -= (face.d == v ? 0 : fs[1]);
    return face;
  }

  // The bit of `around` for the point p + da along axis, du along u and dv
  // along v (each of du, dv in -1..1): the four cells' 3 x 3 x 2 points.
  static constexpr int around_bit(int da, int du, int dv) { return 9 * da + 3 * (dv + 1) + (du + 1); }

  // Inside-ness (label `only`) of the points around the edge from padded
  // point p along axis, as bits (around_bit).
  std::uint32_t around(Id p, int axis) const {
    const LabelIndex* at = vol_.row(p);
    const auto l = static_cast<LabelIndex>(only_);
    std::uint32_t bits = 0;
    for (int b = 0; b < 18; ++b) bits |= static_cast<std::uint32_t>(at[around_[axis][b]] == l) << b;
    return bits;
  }

  // The case of cell m around the edge from its 8 bits of `near`: at
  // du + 3 dv + 9 da past its first corner's bit, gathered to du + 2 dv +
  // 4 da, then ordered as cube corners (x, y, z) by case_of_.
  unsigned cell_case(std::uint32_t near, int axis, int m) const {
    const std::uint32_t b = near >> around_bit(0, -kAround[m][0], -kAround[m][1]);
    const std::uint32_t gathered = (b & 0x3u) | ((b >> 1) & 0xcu) | ((b >> 5) & 0x30u) | ((b >> 6) & 0xc0u);
    return case_of_[axis][gathered];
  }

  // Whether the label sits on one diagonal of the face between cells m and
  // m + 1 around the edge (spanning axis and w; `near` from around).
  bool ambiguous(std::uint32_t near, int axis, int m) const {
    const auto in = [&](int corner) { return ((near >> face_bit_[axis][m][corner]) & 1u) != 0; };
    const bool c00 = in(0), c10 = in(1), c01 = in(2), c11 = in(3);
    return c00 == c11 && c10 == c01 && c00 != c10;
  }

  // The key of the face point after cell m of the edge at lp (`up`: which
  // end carries the label) on `face`, an ambiguous one, or -1 where the
  // face does not pinch.
  Id face_point(const Id lp[3], const Face& face, int axis, int up, int m, const unsigned cube[4]) const {
    // The label's corner of this edge on the face, and the other one.
    const int ow_here = static_cast<int>(lp[face.w] - face.f[face.w]);
    if (!arcs_join(lp, face, axis, ow_here, m, cube)) return -1;
    // The arc around the label's corner (up, ow_here) of the face.
    const Id face_cell = face.f[0] + face.f[1] * cstride_[1] + face.f[2] * cstride_[2];
    const int arc = (face.w < axis ? ow_here : up) ? 1 : 0;  // by the face's first spanning axis
    return 4 * cells_ + 2 * (3 * face_cell + face.d) + arc;
  }

  // Whether, in both cells m and m + 1, the loop of the other arc's edge
  // along axis (from the other corner's w-side, axis offset 0) is this
  // edge's loop.
  bool arcs_join(const Id lp[3], const Face& face, int axis, int ow_here, int m, const unsigned cube[4]) const {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const int ow_other = 1 - ow_here;
    bool pinch = true;
    for (int side : {m, (m + 1) % 4}) {
      // The cell's first corner in box coordinates.
      Id c[3] = {lp[0], lp[1], lp[2]};
      c[u] -= kAround[side][0], c[v] -= kAround[side][1];
      // The other arc's edge along axis sits at w offset ow_other on the face.
      int corner_here = 0, corner_other = 0;
      for (int ax = 0; ax < 3; ++ax) {
        const Id here = ax == axis ? 0 : (ax == face.w ? face.f[face.w] + ow_here : face.f[face.d]) - c[ax];
        const Id other = ax == axis ? 0 : (ax == face.w ? face.f[face.w] + ow_other : face.f[face.d]) - c[ax];
        corner_here |= static_cast<int>(here) << ax;
        corner_other |= static_cast<int>(other) << ax;
      }
      const unsigned cs = cube[side];
      pinch = pinch && loops_.loop_of[cs][loops_.edge_at[corner_here][axis]] ==
                           loops_.loop_of[cs][loops_.edge_at[corner_other][axis]];
    }
    return pinch;
  }

  const LabelVolume& vol_;
  const Box& box_;
  int only_;
  std::pair<Id, Id> krange_;
  const CellLoops& loops_;
  Id cstride_[3], pstride_[3];
  Id cells_;
  Id around_[3][18];                        // per axis: offsets of around's points from p
  std::uint8_t case_of_[3][256];           // per axis: a cell's case from its gathered bits (cell_case)
  std::uint8_t face_bit_[3][4][4];         // per axis, face after cell m, corner (oa + 2 ow): its bit
};

// The most triangles a soup holds: 3 corners each in the 32-bit index map.
constexpr Id kMaxTriangles = Id{std::numeric_limits<std::uint32_t>::max()} / 3;

// The network's quads of every visited edge, counted per row, then written
// as triangles at each row's offset: grid order whatever the thread count.
template <class K>
void generate_quads(const LabelVolume& vol, const Box& box, std::pair<Id, Id> krange, Soup<K>& soup) {
  const EdgePolygons<K> edges(vol, box, -1, krange);
  const Id rows = edges.rows();
  std::vector<Id> row_offsets(static_cast<std::size_t>(rows + 1), 0);
  parallel::for_each_dynamic(rows, [&](Id r) {
    Id count = 0;
    edges.visit_row(r, [&](Id i, Id j, Id k, int axis, LabelIndex a, LabelIndex) {
      count += edges.polygon(i, j, k, axis, a, nullptr) - 2;
    });
    row_offsets[r] = count;
  }, 16);
  const Id triangles = parallel::exclusive_scan(row_offsets.data(), row_offsets.data(), rows + 1);
  if (triangles > kMaxTriangles)
    throw LimitError("labels: " + std::to_string(triangles) + " triangles exceed the supported 1431655765");
  soup.keys.resize(static_cast<std::size_t>(3 * triangles));
  soup.pair.resize(static_cast<std::size_t>(triangles));
  parallel::for_each_dynamic(rows, [&](Id r) {
    Id t = row_offsets[r];
    edges.visit_row(r, [&](Id i, Id j, Id k, int axis, LabelIndex a, LabelIndex b) {
      edges.write_network_quad(i, j, k, axis, a, b, t, soup);
      t += 2;
    });
  }, 16);
}

// Appends the triangles of the polygons of rows [r0, r1) to `soup`, in
// grid order; false once it holds more than kMaxTriangles.
template <class K>
bool append_label_rows(const EdgePolygons<K>& edges, Id r0, Id r1, Soup<K>& soup) {
  for (Id r = r0; r < r1; ++r) {
    edges.visit_row(r, [&](Id i, Id j, Id k, int axis, LabelIndex a, LabelIndex b) {
      K poly[8];
      const int n = edges.polygon(i, j, k, axis, a, poly);
      const Id t = static_cast<Id>(soup.pair.size());
      soup.keys.resize(static_cast<std::size_t>(3 * (t + n - 2)));
      soup.pair.resize(static_cast<std::size_t>(t + n - 2));
      edges.write_fan(poly, n, a, b, t, soup);
    });
    if (static_cast<Id>(soup.pair.size()) > kMaxTriangles) return false;
  }
  return true;
}

// Label `only`'s polygons in one pass (a polygon costs more than the visit
// that finds it, so counting first would nearly double the work): blocks
// of rows each append to their own soup, joined in row order, so the soup
// is the same for any block count. One block writes `soup` itself.
template <class K>
void generate_label_polygons(const LabelVolume& vol, const Box& box, int only, std::pair<Id, Id> krange, Id blocks,
                             Soup<K>& soup) {
  const EdgePolygons<K> edges(vol, box, only, krange);
  const Id rows = edges.rows();
  soup.keys.clear();
  soup.pair.clear();
  bool fits = true;
  if (blocks <= 1) {
    fits = append_label_rows(edges, 0, rows, soup);
  } else {
    std::vector<Soup<K>> part(static_cast<std::size_t>(blocks));
    std::vector<Id> offset(static_cast<std::size_t>(blocks + 1), 0);
    std::vector<std::uint8_t> block_fits(static_cast<std::size_t>(blocks), 1);
    parallel::for_each_dynamic(blocks, [&](Id b) {
      block_fits[b] = append_label_rows(edges, rows * b / blocks, rows * (b + 1) / blocks, part[b]);
      offset[b] = static_cast<Id>(part[b].pair.size());
    }, 1);
    const Id triangles = parallel::exclusive_scan(offset.data(), offset.data(), blocks + 1);
    fits = triangles <= kMaxTriangles && std::all_of(block_fits.begin(), block_fits.end(), [](auto f) { return f != 0; });
    if (fits) {
      soup.keys.resize(static_cast<std::size_t>(3 * triangles));
      soup.pair.resize(static_cast<std::size_t>(triangles));
      parallel::for_each_dynamic(blocks, [&](Id b) {
        std::copy(part[b].keys.begin(), part[b].keys.end(), soup.keys.begin() + 3 * offset[b]);
        std::copy(part[b].pair.begin(), part[b].pair.end(), soup.pair.begin() + offset[b]);
      }, 1);
    }
  }
  if (!fits) throw LimitError("labels: a label's surface has more than the supported 1431655765 triangles");
}

// Appends the welded points of one run: positions, junction and border
// flags, from each point's key (cell, or 4 * cell + piece).
template <class K>
void append_points(const LabelVolume& vol, const Box& box, int only, const std::vector<K>& point_keys,
                   LabelSurface& out) {
  const auto& loops = cell_loops();
  const auto& mc = marching_cubes_table();
  const CellCorners corners(vol);
  const Id base = static_cast<Id>(out.junction.size());
  const Id n = static_cast<Id>(point_keys.size());
  out.mesh.points.resize(static_cast<std::size_t>(3 * (base + n)));
  out.cell_centre.resize(static_cast<std::size_t>(3 * (base + n)));
  out.junction.resize(static_cast<std::size_t>(base + n));
  out.border_axes.resize(static_cast<std::size_t>(base + n));
  if (vol.coarse_keys) out.coarse.resize(static_cast<std::size_t>(base + n));
  const Id cells = box.cells();
  const label_kernels::Placement place = placement(vol);
  parallel::for_each(n, [&](Id pt) {
    const Id key = static_cast<Id>(point_keys[static_cast<std::size_t>(pt)]);
    const std::size_t at = static_cast<std::size_t>(base + pt);
    if (only >= 0 && key >= 4 * cells) {
      // A face point: on the face, a quarter spacing from the label's corner
      // of its arc towards the face's centre.
      const Id fk = key - 4 * cells, arc = fk % 2, face = fk / 2;
      const int d = static_cast<int>(face % 3);
      const Id fc = face / 3;
      const Id f[3] = {box.lo[0] + fc % box.cx(), box.lo[1] + (fc / box.cx()) % (box.dims[1] - 1),
                       box.lo[2] + fc / box.cxy()};
      const int s1 = d == 0 ? 1 : 0, s2 = d == 2 ? 1 : 2;  // spanning axes, s1 < s2
      const bool c00 = vol.label(vol.at(f[0], f[1], f[2])) == only;
      // The arc's corner: offsets along s1 and s2.
      const int o1 = static_cast<int>(arc), o2 = c00 ? o1 : 1 - o1;
      for (int a = 0; a < 3; ++a) {
        double g = static_cast<double>(f[a]);
        if (a == s1) g += o1 ? 0.75 : 0.25;
        if (a == s2) g += o2 ? 0.75 : 0.25;
        const double x = vol.coord(a, g);
        out.mesh.points[3 * at + a] = static_cast<float>(x);
        out.cell_centre[3 * at + a] = static_cast<float>(x);
      }
      out.border_axes[at] = 0;
      out.junction[at] = CellCorners::distinct(corners.labels(vol.at(f[0], f[1], f[2]))) >= 3;  // the cell at f
      if (vol.coarse_keys)
        out.coarse[at] = vol.part_key(vol.block_key(f[0], f[1], f[2]), static_cast<LabelIndex>(only));
      return;
    }
    const Id cell = only < 0 ? key : key / 4;
    const Id local[3] = {cell % box.cx(), (cell / box.cx()) % (box.dims[1] - 1), cell / box.cxy()};
    const Id g[3] = {box.lo[0] + local[0], box.lo[1] + local[1], box.lo[2] + local[2]};
    const std::array<LabelIndex, 8> corner = corners.labels(vol.at(g[0], g[1], g[2]));
    double offset[3] = {0, 0, 0};
    if (only >= 0) {
      // A cell with several loops: each loop's point sits at the centroid
      // of its cut edges' midpoints (its marching cubes polygon), so the
      // points do not coincide; a single loop keeps the cell centre.
      const unsigned cube = CellCorners::case_of(corner, static_cast<LabelIndex>(only));
      if (loops.loops[cube] > 1) {
        const int loop = static_cast<int>(key % 4);
        int count = 0;
        double sum[3] = {0, 0, 0};
        for (int e = 0; e < 12; ++e) {
          const auto& ce = mc.edges[e];
          if (((cube >> ce.corner0) & 1) == ((cube >> ce.corner1) & 1) || loops.loop_of[cube][e] != loop) continue;
          ++count;
          const double mid[3] = {ce.dx + (ce.axis == 0 ? 0.5 : 0.0), ce.dy + (ce.axis == 1 ? 0.5 : 0.0),
                                 ce.dz + (ce.axis == 2 ? 0.5 : 0.0)};
          for (int a = 0; a < 3; ++a) sum[a] += mid[a] - 0.5;
        }
        for (int a = 0; a < 3; ++a) offset[a] = sum[a] / count;
      }
    }
    out.border_axes[at] = place.cell_point(g, offset, &out.mesh.points[3 * at], &out.cell_centre[3 * at]);
    out.junction[at] = CellCorners::distinct(corner) >= 3;
    if (vol.coarse_keys) out.coarse[at] = vol.part_key(vol.block_key(g[0], g[1], g[2]), static_cast<LabelIndex>(only));
  }, 1024);
}

// Welds one soup (dense plan over the box's keys; a sort in a window of a
// streamed volume, whose keys span far more than it holds: the same groups)
// and appends it to `out`, with the points' keys in a window.
template <class K>
void weld_and_append(const LabelVolume& vol, const Box& box, int only, Soup<K>& soup, LabelSurface& out) {
  const K range = static_cast<K>(only < 0 ? box.cells() : (4 + kFaceKeysPerCell) * box.cells());
  const Id n = static_cast<Id>(soup.keys.size());
  auto groups = vol.window ? keyreduce::partition_sort(soup.keys.data(), n, parallel::bits_needed<K>(range),
                                                       keyreduce::Order::Skip)
                           : keyreduce::partition_dense(soup.keys.data(), n, range, keyreduce::Order::Skip);
  const std::uint32_t base = static_cast<std::uint32_t>(out.junction.size());
  const std::size_t c0 = out.mesh.connectivity.size();
  if (c0 == 0 && base == 0) {
    out.mesh.connectivity = std::move(groups.index_map);  // the first run: the index map is the connectivity
  } else {
    out.mesh.connectivity.resize(c0 + groups.index_map.size());
    parallel::for_each(static_cast<Id>(groups.index_map.size()), [&](Id i) {
      out.mesh.connectivity[c0 + static_cast<std::size_t>(i)] = base + groups.index_map[i];
    });
  }
  out.pair.insert(out.pair.end(), soup.pair.begin(), soup.pair.end());
  append_points(vol, box, only, groups.unique_keys, out);
  if (vol.window || vol.keep_keys) out.keys.insert(out.keys.end(), groups.unique_keys.begin(), groups.unique_keys.end());
}

Box whole(const LabelVolume& vol) { return Box{{0, 0, 0}, vol.dims}; }

// The label's voxels' box grown by one point each way: every edge with an
// end of the label, and every cell around such an edge, lies in it.
Box box_of(const LabelVolume& vol, std::size_t s) {
  Box b;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = vol.box[s][a] - 1;
    b.dims[a] = vol.box[s][3 + a] - vol.box[s][a] + 3;
  }
  return b;
}

// Edge rows [rows.first, rows.second) of the padded grid, in box coordinates
// (empty when the box lies outside them).
std::pair<Id, Id> rows_in(const Box& box, std::pair<Id, Id> rows) {
  const Id b = std::max<Id>(rows.first - box.lo[2], 0), e = std::min<Id>(rows.second - box.lo[2], box.dims[2]);
  return {b, std::max(b, e)};
}

template <class K>
void network(const LabelVolume& vol, std::pair<Id, Id> rows, LabelSurface& out, LabelStats& st) {
  Soup<K> soup;
  const Box box = whole(vol);
  auto t0 = Clock::now();
  generate_quads<K>(vol, box, rows, soup);
  st.generate += seconds_since(t0);
  st.soup_corners += static_cast<Id>(soup.keys.size());
  t0 = Clock::now();
  weld_and_append(vol, box, -1, soup, out);
  st.weld += seconds_since(t0);
}

// Label part s's closed surface on its box into `out`. Its keys stay 64-bit
// where 32 would hold them: 32-bit keys made the same bits with no fewer
// instructions, and more page faults (AAL, 2026-11-29).
void label_surface(const LabelVolume& vol, std::size_t s, std::pair<Id, Id> rows, Id blocks, LabelSurface& out) {
  const Box box = box_of(vol, s);
  const int label = vol.selected[s];
  Soup<std::uint64_t> soup;
  generate_label_polygons(vol, box, label, rows_in(box, rows), blocks, soup);
  weld_and_append(vol, box, label, soup, out);
  out.mesh.cell_fields.push_back(Field{"label", 1, Array<float>(soup.pair.size(), static_cast<float>(vol.values[label]))});
}

// One closed surface per selected label, each welded on its own box; the
// labels run in parallel (a single label: its blocks of rows do).
std::vector<LabelSurface> per_label(const LabelVolume& vol, std::pair<Id, Id> rows, LabelStats& st) {
  const std::size_t n = vol.selected.size();
  std::vector<LabelSurface> parts(n);
  const int threads = parallel::thread_count();
  const Id blocks = n > 1 || threads <= 1 ? 1 : 4 * threads;
  auto t0 = Clock::now();
  parallel::for_each_dynamic(static_cast<Id>(n), [&](Id s) {
    const auto at = static_cast<std::size_t>(s);
    label_surface(vol, at, rows, blocks, parts[at]);
  }, 1);
  st.generate += seconds_since(t0);
  for (const LabelSurface& p : parts) st.soup_corners += static_cast<Id>(p.mesh.connectivity.size());
  return parts;
}

}  // namespace

LabelSurface surface_nets(const LabelVolume& volume, bool per_label_surfaces, LabelStats& stats) {
  LabelSurface out;
  out.quads = !per_label_surfaces;  // per label, face points make some polygons longer than quads
  const std::pair<Id, Id> rows{0, volume.dims[2]};
  if (per_label_surfaces) {
    auto parts = per_label(volume, rows, stats);
    append_surfaces(parts, out);
  } else if (static_cast<std::uint64_t>(whole(volume).cells()) <= std::numeric_limits<std::uint32_t>::max()) {
    network<std::uint32_t>(volume, rows, out, stats);
  } else {
    network<std::uint64_t>(volume, rows, out, stats);
  }
  return out;
}

std::vector<LabelSurface> surface_nets_rows(const LabelVolume& window, bool per_label_surfaces,
                                            std::pair<Id, Id> rows, LabelStats& stats) {
  if (per_label_surfaces) return per_label(window, rows, stats);
  std::vector<LabelSurface> out(1);
  out[0].quads = true;
  network<std::uint64_t>(window, rows, out[0], stats);
  return out;
}

}  // namespace keymesh::generate::detail
