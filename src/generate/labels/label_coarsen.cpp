// Coarsening of a welded label surface (see keymesh/generate/labels/labels.hpp):
// one KEY-REDUCE over the points' coarse keys merges them (positions
// averaged in increasing index, so any thread count gives the same bits),
// the index map rewrites the faces, collapsed faces are dropped, and faces
// of one label pair (and label) on the same three points cancel by
// orientation, keeping every label's faces a closed 2-cycle.
#include <algorithm>
#include <chrono>

#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"
#include "keymesh/parallel/scan.hpp"
#include "label_volume.hpp"

namespace keymesh::generate::detail {

namespace {

// A face on three distinct points: the smallest first (a rotation keeps the
// orientation), the other two sorted, and the orientation that took.
struct Face {
  std::uint32_t lo, mid, hi;
  int sign;
  std::uint64_t tag;  // label pair and label: faces cancel only within one tag
};

// Per face: 1 to keep, 0 to drop. Faces are grouped by their smallest point
// (a dense KEY-REDUCE); in each group, faces with equal points and tag have
// net orientation n = sum of signs, and the first |n| of the winning side
// (in face order) stay.
std::vector<Id> cancel_opposite_faces(const std::vector<Face>& faces, Id points) {
  const Id n = static_cast<Id>(faces.size());
  std::vector<Id> keep(static_cast<std::size_t>(n + 1), 1);
  keep[static_cast<std::size_t>(n)] = 0;
  std::vector<std::uint32_t> lo(static_cast<std::size_t>(n));
  parallel::for_each(n, [&](Id f) { lo[static_cast<std::size_t>(f)] = faces[static_cast<std::size_t>(f)].lo; });
  const auto g = keyreduce::partition_dense(lo.data(), n, static_cast<std::uint32_t>(points), keyreduce::Order::Build);
  parallel::for_each(g.num_groups(), [&](Id grp) {
    const Id b = g.offsets[grp], e = g.offsets[grp + 1];
    auto same = [&](const Face& x, const Face& y) { return x.mid == y.mid && x.hi == y.hi && x.tag == y.tag; };
    for (Id i = b; i < e; ++i) {
      const Face& fi = faces[g.order[i]];
      bool first = true;
      for (Id j = b; j < i && first; ++j) first = !same(faces[g.order[j]], fi);
      if (!first) continue;  // decided with the first of its set
      int net = 0;
      for (Id j = i; j < e; ++j)
        if (same(faces[g.order[j]], fi)) net += faces[g.order[j]].sign;
      int left = std::abs(net);
      for (Id j = i; j < e; ++j) {  // order[] runs in face order within a group
        const Face& fj = faces[g.order[j]];
        if (!same(fj, fi)) continue;
        const bool stays = left > 0 && (fj.sign > 0) == (net > 0);
        keep[g.order[j]] = stays ? 1 : 0;
        left -= stays ? 1 : 0;
      }
    }
  }, 256);
  return keep;
}

// Per coarse point (group of g), the mean of its points' positions, summed
// in increasing index so any thread count gives the same bits.
std::vector<float> merged_positions(const LabelSurface& s, const keyreduce::Groups<std::uint64_t>& g) {
  const Id m = g.num_groups();
  std::vector<float> merged(static_cast<std::size_t>(3 * m));
  parallel::for_each(m, [&](Id p) {
    for (int a = 0; a < 3; ++a) {
      double sum = 0;
      for (Id j = g.offsets[p]; j < g.offsets[p + 1]; ++j) sum += s.mesh.points[3 * static_cast<std::size_t>(g.order[j]) + a];
      merged[static_cast<std::size_t>(3 * p + a)] = static_cast<float>(sum / static_cast<double>(g.count(p)));
    }
  }, 1024);
  return merged;
}

// The faces through the index map; collapsed ones (fewer than three
// distinct points) get sign 0, to be dropped.
std::vector<Face> mapped_faces(const LabelSurface& s, const keyreduce::Groups<std::uint64_t>& g) {
  const Id faces_in = static_cast<Id>(s.pair.size());
  const Field* label = s.mesh.find_cell_field("label");
  std::vector<Face> faces(static_cast<std::size_t>(faces_in));
  const PointIndex* C = s.mesh.connectivity.data();
  parallel::for_each(faces_in, [&](Id t) {
    const std::uint32_t v[3] = {g.index_map[C[3 * t]], g.index_map[C[3 * t + 1]], g.index_map[C[3 * t + 2]]};
    const int r = v[0] < v[1] ? (v[0] < v[2] ? 0 : 2) : (v[1] < v[2] ? 1 : 2);
    const std::uint32_t a = v[r], b = v[(r + 1) % 3], c = v[(r + 2) % 3];
    const bool collapsed = a == b || b == c || a == c;
    const std::uint64_t tag =
        std::uint64_t{s.pair[static_cast<std::size_t>(t)]} << 32 |
        (label ? static_cast<std::uint32_t>(static_cast<std::int64_t>(label->values[static_cast<std::size_t>(t)]) +
                                            kMaxLabelMagnitude)
               : 0u);
    faces[static_cast<std::size_t>(t)] = Face{a, std::min(b, c), std::max(b, c), collapsed ? 0 : (b < c ? 1 : -1), tag};
  }, 4096);
  return faces;
}

// Keeps the faces `keep` marks (its exclusive scan: face t stays, at
// keep[t], where keep[t + 1] differs) with their pair, ghost flag and cell
// fields; their corners become coarse point indices.
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
// placed at their merged positions. Returns the number of points left.
Id keep_used_points(LabelSurface& s, const keyreduce::Groups<std::uint64_t>& g, const std::vector<float>& merged) {
  const Id m = g.num_groups();
  Array<PointIndex>& conn = s.mesh.connectivity;
  const Id corners = static_cast<Id>(conn.size());
  std::vector<Id> used(static_cast<std::size_t>(m + 1), 0);
  parallel::for_each(corners, [&](Id k) { used[conn[static_cast<std::size_t>(k)]] = 1; });
  const Id m_used = parallel::exclusive_scan(used.data(), used.data(), m + 1);
  Array<float> compact(static_cast<std::size_t>(3 * m_used));
  // A streamed surface's points keep their keys: now the coarse ones.
  std::vector<std::uint64_t> keys(s.keys.empty() ? 0 : static_cast<std::size_t>(m_used));
  parallel::for_each(m, [&](Id p) {
    if (used[static_cast<std::size_t>(p + 1)] == used[static_cast<std::size_t>(p)]) return;
    std::copy_n(merged.begin() + 3 * p, 3, compact.begin() + 3 * used[static_cast<std::size_t>(p)]);
    if (!keys.empty()) keys[static_cast<std::size_t>(used[static_cast<std::size_t>(p)])] = g.unique_keys[static_cast<std::size_t>(p)];
  });
  parallel::for_each(corners, [&](Id k) {
    conn[static_cast<std::size_t>(k)] = static_cast<PointIndex>(used[conn[static_cast<std::size_t>(k)]]);
  });
  s.mesh.points = std::move(compact);
  s.keys = std::move(keys);
  return m_used;
}

}  // namespace

void coarsen_label_surface(LabelSurface& s, LabelStats& st) {
  const auto t0 = std::chrono::steady_clock::now();
  const Id points = static_cast<Id>(s.coarse.size());
  const Id faces_in = static_cast<Id>(s.pair.size());
  st.triangles_before_coarsening = faces_in;
  const std::uint64_t top = s.coarse.empty() ? 0 : *std::max_element(s.coarse.begin(), s.coarse.end());
  const auto g = keyreduce::partition_sort(s.coarse.data(), points, parallel::bits_needed<std::uint64_t>(top),
                                           keyreduce::Order::Build);
  const std::vector<float> merged = merged_positions(s, g);
  const std::vector<Face> faces = mapped_faces(s, g);
  std::vector<Id> keep = cancel_opposite_faces(faces, g.num_groups());
  parallel::for_each(faces_in, [&](Id t) {
    if (faces[static_cast<std::size_t>(t)].sign == 0) keep[static_cast<std::size_t>(t)] = 0;
  });
  parallel::exclusive_scan(keep.data(), keep.data(), faces_in + 1);
  keep_faces(s, g, keep);
  const Id m_used = keep_used_points(s, g, merged);
  s.quads = false;
  s.junction.assign(static_cast<std::size_t>(m_used), 0);
  s.border_axes.assign(static_cast<std::size_t>(m_used), 0);
  s.cell_centre.clear();
  s.coarse.clear();
  st.coarsen = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace keymesh::generate::detail
