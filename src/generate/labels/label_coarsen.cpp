// Coarsening of a welded label surface (see keymesh/generate/labels/labels.hpp):
// one KEY-REDUCE over the points' coarse keys merges them (positions
// averaged in increasing index, so any thread count gives the same bits),
// the index map rewrites the faces, collapsed faces are dropped, and faces
// of one label pair (and label) on the same three points cancel by
// orientation, keeping every label's faces a closed 2-cycle. The same steps
// coarsen a multilod chunk piece (merge_piece_points), read in place; small
// inputs group serially (a hash of the keys, first_seen_keys.hpp, and a sort
// of the distinct ones), large ones by the parallel plans, with the same
// result (label_chunks.hpp, kCoarsenSerialBelow).
#include <algorithm>
#include <chrono>
#include <numeric>

#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"
#include "first_seen_keys.hpp"
#include "label_chunks.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

// A face on three distinct points: the smallest first (a rotation keeps the
// orientation), the other two sorted, and the orientation that took.
struct Face {
  std::uint32_t lo, mid, hi;
  int sign;           // 0: collapsed (fewer than three distinct points)
  std::uint64_t tag;  // label pair and label: faces cancel only within one tag
};

// What coarsening reads: a surface's points, faces and their tags, and a
// coarse key per point.
struct CoarsenInput {
  const float* points = nullptr;
  const PointIndex* connectivity = nullptr;
  Id faces = 0;
  const std::uint64_t* coarse = nullptr;
  Id coarse_count = 0;
  const std::uint32_t* pair = nullptr;  // per face, or none: all 0
  const Field* label = nullptr;         // per face, or none
  Id serial_below = kCoarsenSerialBelow;
};

// The points grouped by coarse key (keyreduce::Groups with Order::Build):
// groups in increasing key, each group's points in increasing index.
keyreduce::Groups<std::uint64_t> group_points(const std::uint64_t* coarse, Id n, Id serial_below) {
  if (n >= serial_below) {
    const std::uint64_t top = n == 0 ? 0 : *std::max_element(coarse, coarse + n);
    return keyreduce::partition_sort(coarse, n, parallel::bits_needed<std::uint64_t>(top), keyreduce::Order::Build);
  }
  // Only the distinct keys are sorted; the points then fall into their
  // groups by a counting sort over increasing index (stable).
  const FirstSeenKeys f = first_seen_keys(coarse, n);
  const std::size_t m = f.keys.size();
  std::vector<std::uint32_t> by_key(m);
  std::iota(by_key.begin(), by_key.end(), 0u);
  std::sort(by_key.begin(), by_key.end(), [&](std::uint32_t x, std::uint32_t y) { return f.keys[x] < f.keys[y]; });
  keyreduce::Groups<std::uint64_t> g;
  g.unique_keys.resize(m);
  g.offsets.resize(m + 1);
  std::vector<std::uint32_t> rank(f.count.size()), next(f.count.size());
  Id at = 0;
  for (std::size_t r = 0; r < m; ++r) {
    const std::uint32_t s = by_key[r];
    rank[s] = static_cast<std::uint32_t>(r);
    g.unique_keys[r] = f.keys[s];
    g.offsets[r] = at;
    next[r] = static_cast<std::uint32_t>(at);
    at += f.count[s];
  }
  g.offsets[m] = n;
  g.index_map.resize(static_cast<std::size_t>(n));
  g.order.resize(static_cast<std::size_t>(n));
  for (Id i = 0; i < n; ++i) {
    const std::uint32_t r = rank[f.of_point[static_cast<std::size_t>(i)]];
    g.index_map[static_cast<std::size_t>(i)] = r;
    g.order[next[r]++] = static_cast<std::uint32_t>(i);
  }
  return g;
}

// The faces of one least point (order[b, e), in face order): faces with
// equal points and tag have net orientation n = sum of signs, and the first
// |n| of the winning side (in face order) stay; the others get keep 0.
void cancel_in_group(const std::vector<Face>& faces, const std::uint32_t* order, Id b, Id e, std::vector<Id>& keep) {
  auto same = [&](const Face& x, const Face& y) { return x.mid == y.mid && x.hi == y.hi && x.tag == y.tag; };
  for (Id i = b; i < e; ++i) {
    const Face& fi = faces[order[i]];
    bool first = true;
    for (Id j = b; j < i && first; ++j) first = !same(faces[order[j]], fi);
    if (!first) continue;  // decided with the first of its set
    int net = 0;
    for (Id j = i; j < e; ++j)
      if (same(faces[order[j]], fi)) net += faces[order[j]].sign;
    int left = std::abs(net);
    for (Id j = i; j < e; ++j) {
      const Face& fj = faces[order[j]];
      if (!same(fj, fi)) continue;
      const bool stays = left > 0 && (fj.sign > 0) == (net > 0);
      keep[order[j]] = stays ? 1 : 0;
      left -= stays ? 1 : 0;
    }
  }
}

// Per face: 1 to keep, 0 to drop (then a 0 past the end, for the scan).
// Collapsed faces are dropped; the others are grouped by their smallest
// point and cancelled within each group (cancel_in_group). A collapsed face
// never has the points of one that is not (lo < mid < hi there), so leaving
// them out of the groups changes no set.
std::vector<Id> cancel_opposite_faces(const std::vector<Face>& faces, Id points, Id serial_below) {
  const Id n = static_cast<Id>(faces.size());
  std::vector<Id> keep(static_cast<std::size_t>(n + 1), 1);
  keep[static_cast<std::size_t>(n)] = 0;
  if (n < serial_below) {  // a counting sort by least point
    const std::size_t m = static_cast<std::size_t>(points);
    std::vector<std::uint32_t> start(m + 2, 0);
    for (std::size_t f = 0; f < faces.size(); ++f) {
      if (faces[f].sign == 0) keep[f] = 0;
      else ++start[faces[f].lo + 2];
    }
    for (std::size_t p = 2; p < m + 2; ++p) start[p] += start[p - 1];
    std::vector<std::uint32_t> order(start[m + 1]);
    for (std::size_t f = 0; f < faces.size(); ++f)
      if (faces[f].sign != 0) order[start[faces[f].lo + 1]++] = static_cast<std::uint32_t>(f);
    for (std::size_t p = 0; p < m; ++p) cancel_in_group(faces, order.data(), start[p], start[p + 1], keep);
    return keep;
  }
  // Parallel: a dense KEY-REDUCE, collapsed faces in one group of their own
  // (key `points`) that is never looked at.
  std::vector<std::uint32_t> lo(static_cast<std::size_t>(n));
  parallel::for_each(n, [&](Id f) {
    const Face& x = faces[static_cast<std::size_t>(f)];
    lo[static_cast<std::size_t>(f)] = x.sign == 0 ? static_cast<std::uint32_t>(points) : x.lo;
    if (x.sign == 0) keep[static_cast<std::size_t>(f)] = 0;
  });
  const auto g =
      keyreduce::partition_dense(lo.data(), n, static_cast<std::uint32_t>(points + 1), keyreduce::Order::Build);
  parallel::for_each(g.num_groups(), [&](Id grp) {
    if (g.unique_keys[static_cast<std::size_t>(grp)] != static_cast<std::uint32_t>(points))
      cancel_in_group(faces, g.order.data(), g.offsets[grp], g.offsets[grp + 1], keep);
  }, 256);
  return keep;
}

// Per coarse point (group of g), the mean of its points' positions, summed
// in increasing index so any thread count gives the same bits.
std::vector<float> merged_positions(const float* points, const keyreduce::Groups<std::uint64_t>& g) {
  const Id m = g.num_groups();
  std::vector<float> merged(static_cast<std::size_t>(3 * m));
  parallel::for_each(m, [&](Id p) {
    double sum[3] = {0, 0, 0};
    for (Id j = g.offsets[p]; j < g.offsets[p + 1]; ++j) {
      const float* q = points + 3 * static_cast<std::size_t>(g.order[j]);
      for (int a = 0; a < 3; ++a) sum[a] += q[a];
    }
    for (int a = 0; a < 3; ++a)
      merged[static_cast<std::size_t>(3 * p + a)] = static_cast<float>(sum[a] / static_cast<double>(g.count(p)));
  }, 1024);
  return merged;
}

// The faces through the index map; collapsed ones (fewer than three
// distinct points) get sign 0, to be dropped.
std::vector<Face> mapped_faces(const CoarsenInput& in, const keyreduce::Groups<std::uint64_t>& g) {
  std::vector<Face> faces(static_cast<std::size_t>(in.faces));
  const PointIndex* C = in.connectivity;
  parallel::for_each(in.faces, [&](Id t) {
    const std::size_t f = static_cast<std::size_t>(t);
    const std::uint32_t v[3] = {g.index_map[C[3 * t]], g.index_map[C[3 * t + 1]], g.index_map[C[3 * t + 2]]};
    const int r = v[0] < v[1] ? (v[0] < v[2] ? 0 : 2) : (v[1] < v[2] ? 1 : 2);
    const std::uint32_t a = v[r], b = v[(r + 1) % 3], c = v[(r + 2) % 3];
    const bool collapsed = a == b || b == c || a == c;
    const std::uint64_t pair = in.pair ? std::uint64_t{in.pair[f]} << 32 : 0;
    const std::uint32_t label =
        in.label ? static_cast<std::uint32_t>(static_cast<std::int64_t>(in.label->values[f]) + kMaxLabelMagnitude) : 0u;
    const std::uint64_t tag = pair | label;
    faces[f] = Face{a, std::min(b, c), std::max(b, c), collapsed ? 0 : (b < c ? 1 : -1), tag};
  }, 4096);
  return faces;
}

// Groups, merged positions and kept faces (keep: the exclusive scan of the
// keep flags: face t stays, at keep[t], where keep[t + 1] differs).
struct Merge {
  keyreduce::Groups<std::uint64_t> groups;
  std::vector<float> merged;
  std::vector<Id> keep;
};

Merge merge_points(const CoarsenInput& in) {
  Merge out;
  out.groups = group_points(in.coarse, in.coarse_count, in.serial_below);
  out.merged = merged_positions(in.points, out.groups);
  const std::vector<Face> faces = mapped_faces(in, out.groups);
  out.keep = cancel_opposite_faces(faces, out.groups.num_groups(), in.serial_below);
  parallel::exclusive_scan(out.keep.data(), out.keep.data(), in.faces + 1);
  return out;
}

// Keeps the faces `keep` marks with their pair, ghost flag and cell fields;
// their corners become coarse point indices.
void keep_faces(LabelSurface& s, const keyreduce::Groups<std::uint64_t>& g, const std::vector<Id>& keep) {
  const Id faces_in = static_cast<Id>(s.pair.size());
  const Id faces_out = keep[static_cast<std::size_t>(faces_in)];
  Array<PointIndex> conn(static_cast<std::size_t>(3 * faces_out));  // every element written below
  std::vector<std::uint32_t> pair(static_cast<std::size_t>(faces_out));
  std::vector<std::uint8_t> ghost(s.ghost_face.empty() ? 0 : static_cast<std::size_t>(faces_out));
  std::vector<Field> fields;
  for (const Field& f : s.mesh.cell_fields)
    fields.push_back(Field{f.name, f.components, Array<float>(static_cast<std::size_t>(faces_out * f.components))});
  const PointIndex* C = s.mesh.connectivity.data();
  parallel::for_each(faces_in, [&](Id t) {
    const Id at = keep[static_cast<std::size_t>(t)];
    if (keep[static_cast<std::size_t>(t + 1)] == at) return;
    for (int k = 0; k < 3; ++k) conn[static_cast<std::size_t>(3 * at + k)] = g.index_map[C[3 * t + k]];
    pair[static_cast<std::size_t>(at)] = s.pair[static_cast<std::size_t>(t)];
    if (!ghost.empty()) ghost[static_cast<std::size_t>(at)] = s.ghost_face[static_cast<std::size_t>(t)];
    for (std::size_t i = 0; i < fields.size(); ++i) {
      const int c = fields[i].components;
      std::copy_n(s.mesh.cell_fields[i].values.begin() + c * t, c, fields[i].values.begin() + c * at);
    }
  }, 4096);
  s.mesh.connectivity = std::move(conn);
  s.mesh.cell_fields = std::move(fields);
  s.pair = std::move(pair);
  s.ghost_face = std::move(ghost);
}

// Points no kept face uses (every face through them collapsed or
// cancelled) are dropped, the others renumbered in coarse-key order and
// placed at their merged positions into `points` (and their coarse keys
// into `keys`, where given). Returns the number of points left.
template <class Connectivity, class Points>
Id keep_used_points(Connectivity& conn, const Merge& merge, Points& points, std::vector<std::uint64_t>* keys) {
  const keyreduce::Groups<std::uint64_t>& g = merge.groups;
  const Id m = g.num_groups();
  const Id corners = static_cast<Id>(conn.size());
  std::vector<Id> used(static_cast<std::size_t>(m + 1), 0);
  parallel::for_each(corners, [&](Id k) { used[conn[static_cast<std::size_t>(k)]] = 1; });
  const Id m_used = parallel::exclusive_scan(used.data(), used.data(), m + 1);
  Points compact(static_cast<std::size_t>(3 * m_used));
  if (keys) keys->resize(static_cast<std::size_t>(m_used));
  parallel::for_each(m, [&](Id p) {
    const Id at = used[static_cast<std::size_t>(p)];
    if (used[static_cast<std::size_t>(p + 1)] == at) return;
    std::copy_n(merge.merged.begin() + 3 * p, 3, compact.begin() + 3 * at);
    if (keys) (*keys)[static_cast<std::size_t>(at)] = g.unique_keys[static_cast<std::size_t>(p)];
  });
  parallel::for_each(corners, [&](Id k) {
    conn[static_cast<std::size_t>(k)] = static_cast<PointIndex>(used[conn[static_cast<std::size_t>(k)]]);
  });
  points = std::move(compact);
  return m_used;
}

}  // namespace

void coarsen_label_surface(LabelSurface& s, LabelStats& st) {
  const auto t0 = std::chrono::steady_clock::now();
  CoarsenInput in;
  in.points = s.mesh.points.data();
  in.connectivity = s.mesh.connectivity.data();
  in.faces = static_cast<Id>(s.pair.size());
  in.coarse = s.coarse.data();
  in.coarse_count = static_cast<Id>(s.coarse.size());
  in.pair = s.pair.data();
  in.label = s.mesh.find_cell_field("label");
  st.triangles_before_coarsening = in.faces;
  const Merge merge = merge_points(in);
  keep_faces(s, merge.groups, merge.keep);
  // A streamed surface's points keep their keys: now the coarse ones.
  const Id m_used = keep_used_points(s.mesh.connectivity, merge, s.mesh.points, s.keys.empty() ? nullptr : &s.keys);
  s.quads = false;
  s.junction.assign(static_cast<std::size_t>(m_used), 0);
  s.border_axes.assign(static_cast<std::size_t>(m_used), 0);
  s.cell_centre.clear();
  s.coarse.clear();
  st.coarsen = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void merge_piece_points(const MultilodPiece& finer, const std::vector<std::uint64_t>& coarse, MultilodPiece& out,
                        Id serial_below) {
  CoarsenInput in;
  in.serial_below = serial_below;
  in.points = finer.points.data();
  in.connectivity = finer.triangles.data();
  in.faces = static_cast<Id>(finer.triangles.size() / 3);
  in.coarse = coarse.data();
  in.coarse_count = static_cast<Id>(coarse.size());
  const Merge merge = merge_points(in);
  const Id faces_out = merge.keep[static_cast<std::size_t>(in.faces)];
  out.triangles.resize(static_cast<std::size_t>(3 * faces_out));
  for (Id t = 0; t < in.faces; ++t) {
    const Id at = merge.keep[static_cast<std::size_t>(t)];
    if (merge.keep[static_cast<std::size_t>(t + 1)] == at) continue;
    for (int k = 0; k < 3; ++k)
      out.triangles[static_cast<std::size_t>(3 * at + k)] = merge.groups.index_map[in.connectivity[3 * t + k]];
  }
  keep_used_points(out.triangles, merge, out.points, &out.point_keys);
}

}  // namespace keymesh::generate::detail
