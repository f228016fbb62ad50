#include "keymesh/generate/split_nonmanifold.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"
#include "keymesh/parallel/scan.hpp"

namespace keymesh::generate {

namespace {

// The corners after and before corner c in its triangle: at c's point, the
// point there is the end of the edge leaving it and the start of the edge
// arriving at it.
std::uint32_t next_corner(std::uint32_t c) { return c % 3 == 2 ? c - 2 : c + 1; }
std::uint32_t prev_corner(std::uint32_t c) { return c % 3 == 0 ? c + 2 : c - 1; }

std::uint64_t edge_key(PointIndex a, PointIndex b) {
  return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
}

// The common point, checked without building its fans: walking from each
// corner's leaving edge to the corner whose arriving edge it is visits all
// d corners before it returns. Taking the first such corner is enough: a
// second corner with the same arriving edge would never be reached, so a
// full walk proves every edge at v has one triangle leaving and one
// arriving. The order of `list` does not matter. Anything else goes to
// FanRule.
bool one_closed_fan(PointIndex v, const PointIndex* next, const PointIndex* prev, Id d) {
  if (d < 3) return false;
  Id j = 0, steps = 0;
  do {
    const PointIndex w = next[j];
    if (w == v) return false;
    Id i = 0;
    while (i < d && prev[i] != w) ++i;
    if (i == d) return false;
    j = i;
  } while (++steps < d && j != 0);
  return j == 0 && steps == d;
}

// The same for corners given by index (the few points looked at again).
bool one_closed_fan(const PointIndex* C, PointIndex v, const std::uint32_t* list, Id d) {
  constexpr Id kMax = 64;
  if (d > kMax) return false;
  PointIndex next[kMax], prev[kMax];
  for (Id j = 0; j < d; ++j) next[j] = C[next_corner(list[j])], prev[j] = C[prev_corner(list[j])];
  return one_closed_fan(v, next, prev, d);
}

// A point's fans under the pairing rule (see the header): its corners
// (`list`, d of them, increasing) united through paired edges; labels[j] is
// the smallest local index of corner j's fan.
struct FanRule {
  const PointIndex* C;
  const std::vector<std::uint64_t>& multi;      // edges with two pairs or more, by key
  const std::vector<std::uint32_t>& rotation;   // their pairings' rotations (empty: none yet)

  // The local indices of v's corners whose edge leaves v for w (`leaving`)
  // or arrives from w, in increasing corner index: the same triangles in the
  // same order as seen from w, with the directions swapped.
  static void half_edges(const PointIndex* C, const std::uint32_t* list, Id d, PointIndex w, bool leaving,
                         std::vector<std::uint32_t>& out) {
    out.clear();
    for (Id j = 0; j < d; ++j)
      if (C[leaving ? next_corner(list[j]) : prev_corner(list[j])] == w) out.push_back(static_cast<std::uint32_t>(j));
  }

  // Scratch, kept between calls (the rule runs on one thread).
  mutable std::vector<std::uint64_t> ent;
  mutable std::vector<std::uint32_t> leaving, arriving;

  std::uint32_t rotation_of(std::uint64_t key) const {
    if (rotation.empty()) return 0;
    const auto it = std::lower_bound(multi.begin(), multi.end(), key);
    return it != multi.end() && *it == key ? rotation[it - multi.begin()] : 0;
  }

  // `found` (when given) collects, from the smaller end, the edges with as
  // many triangles each way and at least two of each.
  void operator()(PointIndex v, const std::uint32_t* list, Id d, std::vector<std::uint32_t>& labels,
                  std::vector<std::uint64_t>* found) const {
    ent.clear();  // other end << 32 | arriving << 31 | local index
    for (Id j = 0; j < d; ++j) {
      ent.push_back((std::uint64_t{C[next_corner(list[j])]} << 32) | static_cast<std::uint64_t>(j));
      ent.push_back((std::uint64_t{C[prev_corner(list[j])]} << 32) | (std::uint64_t{1} << 31) |
                    static_cast<std::uint64_t>(j));
    }
    std::sort(ent.begin(), ent.end());
    labels.resize(static_cast<std::size_t>(d));
    for (Id j = 0; j < d; ++j) labels[j] = static_cast<std::uint32_t>(j);
    auto find = [&](std::uint32_t x) {
      while (labels[x] != x) x = labels[x] = labels[labels[x]];
      return x;
    };
    auto unite = [&](std::uint32_t a, std::uint32_t b) {
      a = find(a), b = find(b);
      if (a != b) labels[std::max(a, b)] = std::min(a, b);  // the root is the smallest index
    };
    for (std::size_t g = 0; g < ent.size();) {
      const PointIndex w = static_cast<PointIndex>(ent[g] >> 32);
      leaving.clear(), arriving.clear();
      std::size_t h = g;
      for (; h < ent.size() && (ent[h] >> 32) == w; ++h)
        ((ent[h] >> 31) & 1 ? arriving : leaving).push_back(static_cast<std::uint32_t>(ent[h] & 0x7fffffffu));
      g = h;
      if (w == v) {  // a triangle repeating v: its corners at v stay together
        for (std::uint32_t j : arriving) unite(j, leaving.empty() ? j : leaving.front());
        for (std::uint32_t j : leaving) unite(j, leaving.front());
        continue;
      }
      // Seen from the smaller end, "up" runs from the smaller id to the larger.
      const auto& up = v < w ? leaving : arriving;
      const auto& down = v < w ? arriving : leaving;
      const std::size_t pairs = std::min(up.size(), down.size());
      const bool balanced = up.size() == down.size() && pairs >= 2;
      const std::uint64_t key = edge_key(v, w);
      const std::size_t rot = balanced ? rotation_of(key) : 0;
      if (balanced && found && v < w) found->push_back(key);
      for (std::size_t i = 0; i < pairs; ++i) unite(up[i], down[(i + rot) % down.size()]);
    }
    for (Id j = 0; j < d; ++j) labels[j] = find(static_cast<std::uint32_t>(j));
  }
};

// The points that are not one closed fan, by increasing id, with their
// corners (increasing): the few the rule looks at.
struct Flagged {
  std::vector<PointIndex> point;
  std::vector<std::uint32_t> first{0};  // point k's corners: corners[first[k] .. first[k + 1])
  std::vector<std::uint32_t> corners;

  std::size_t size() const { return point.size(); }
  const std::uint32_t* list(std::size_t k) const { return corners.data() + first[k]; }
  Id degree(std::size_t k) const { return first[k + 1] - first[k]; }
  std::size_t at(PointIndex p) const {
    return static_cast<std::size_t>(std::lower_bound(point.begin(), point.end(), p) - point.begin());
  }
  void add(PointIndex p, const std::uint32_t* list, Id d) {
    point.push_back(p);
    corners.insert(corners.end(), list, list + d);
    first.push_back(static_cast<std::uint32_t>(corners.size()));
  }
};

// Every point's corners (counted, then placed: a counting sort by point id,
// the order within a point left to the threads; 4 bytes a corner), each
// point checked by one_closed_fan; the flagged points' corners sorted, so
// that all after this is deterministic.
Flagged flag_points(const PointIndex* C, Id corners, Id n) {
  std::vector<std::uint32_t> end;  // counts, then each point's first slot, then its end
  parallel::resize_fresh(end, static_cast<std::size_t>(n + 1));
  parallel::for_each(n + 1, [&](Id p) { end[p] = 0; });
  parallel::for_each(corners, [&](Id c) {
    std::atomic_ref<std::uint32_t>(end[C[c]]).fetch_add(1, std::memory_order_relaxed);
  }, 1 << 14);
  parallel::exclusive_scan(end.data(), end.data(), n + 1);
  std::vector<std::uint32_t> list;
  parallel::resize_fresh(list, static_cast<std::size_t>(corners));
  parallel::for_each(corners, [&](Id c) {
    list[std::atomic_ref<std::uint32_t>(end[C[c]]).fetch_add(1, std::memory_order_relaxed)] =
        static_cast<std::uint32_t>(c);
  }, 1 << 14);
  auto begin = [&](Id p) { return p == 0 ? std::uint32_t{0} : end[p - 1]; };
  const int chunks = parallel::chunk_count(n, 1 << 14);
  std::vector<std::vector<PointIndex>> odd(static_cast<std::size_t>(std::max(chunks, 1)));
  parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int chunk) {
    for (Id p = b; p < e; ++p) {
      const Id d = end[p] - begin(p);
      if (d > 0 && !one_closed_fan(C, static_cast<PointIndex>(p), list.data() + begin(p), d))
        odd[chunk].push_back(static_cast<PointIndex>(p));
    }
  });
  Flagged f;
  for (const auto& points : odd)
    for (PointIndex p : points) {
      std::uint32_t* l = list.data() + begin(p);
      std::sort(l, l + (end[p] - begin(p)));
      f.add(p, l, end[p] - begin(p));
    }
  return f;
}

// The corners of `f` regrouped by the ids they hold now; the points that
// are still not one closed fan.
Flagged reflag(const PointIndex* C, const Flagged& f) {
  std::vector<std::uint64_t> by_point(f.corners.size());
  for (std::size_t i = 0; i < f.corners.size(); ++i)
    by_point[i] = (std::uint64_t{C[f.corners[i]]} << 32) | f.corners[i];
  std::sort(by_point.begin(), by_point.end());
  Flagged out;
  std::vector<std::uint32_t> list;
  for (std::size_t i = 0; i < by_point.size();) {
    const PointIndex p = static_cast<PointIndex>(by_point[i] >> 32);
    list.clear();
    for (; i < by_point.size() && (by_point[i] >> 32) == p; ++i) list.push_back(static_cast<std::uint32_t>(by_point[i]));
    const Id d = static_cast<Id>(list.size());
    if (!one_closed_fan(C, p, list.data(), d)) out.add(p, list.data(), d);
  }
  return out;
}

// Every flagged point's fans under the current rotations, recomputed for
// the two ends of an edge whose rotation changes.
struct FanCache {
  const FanRule& fans;
  const Flagged& f;
  std::vector<std::vector<std::uint32_t>> labels;

  FanCache(const FanRule& rule, const Flagged& flagged, std::vector<std::uint64_t>* found)
      : fans(rule), f(flagged), labels(flagged.size()) {
    for (std::size_t k = 0; k < f.size(); ++k) fans(f.point[k], f.list(k), f.degree(k), labels[k], found);
  }
  void refresh(std::uint64_t key) {
    for (PointIndex p : {static_cast<PointIndex>(key >> 32), static_cast<PointIndex>(key & 0xffffffffu)}) {
      const std::size_t k = f.at(p);
      fans(p, f.list(k), f.degree(k), labels[k], nullptr);
    }
  }

  // Whether the edge's pairs join the same fan at both ends twice.
  bool joins_twice(std::uint64_t key) {
    const PointIndex lo = static_cast<PointIndex>(key >> 32), hi = static_cast<PointIndex>(key & 0xffffffffu);
    const std::size_t a = f.at(lo), b = f.at(hi);
    FanRule::half_edges(fans.C, f.list(a), f.degree(a), hi, true, up_lo);
    FanRule::half_edges(fans.C, f.list(b), f.degree(b), lo, false, up_hi);
    ends.resize(up_lo.size());
    for (std::size_t i = 0; i < up_lo.size(); ++i)
      ends[i] = (std::uint64_t{labels[a][up_lo[i]]} << 32) | labels[b][up_hi[i]];
    std::sort(ends.begin(), ends.end());
    return std::adjacent_find(ends.begin(), ends.end()) != ends.end();
  }

 private:
  std::vector<std::uint32_t> up_lo, up_hi;
  std::vector<std::uint64_t> ends;
};

// Sweeps over the multi-edges in key order: a conflicted edge takes the
// first rotation that separates its pairs. Returns the edges left joined.
Id rotate_pairings(FanCache& cache, std::vector<std::uint32_t>& rotation) {
  const std::vector<std::uint64_t>& multi = cache.fans.multi;
  std::vector<std::uint32_t> up;
  for (int sweep = 0; sweep < 4; ++sweep) {
    bool changed = false;
    for (std::size_t e = 0; e < multi.size(); ++e) {
      if (!cache.joins_twice(multi[e])) continue;
      const std::size_t a = cache.f.at(static_cast<PointIndex>(multi[e] >> 32));
      FanRule::half_edges(cache.fans.C, cache.f.list(a), cache.f.degree(a),
                          static_cast<PointIndex>(multi[e] & 0xffffffffu), true, up);
      const std::uint32_t pairs = static_cast<std::uint32_t>(up.size()), was = rotation[e];
      for (std::uint32_t r = 1; r < pairs; ++r) {
        rotation[e] = (was + r) % pairs;
        cache.refresh(multi[e]);
        if (!cache.joins_twice(multi[e])) break;
        rotation[e] = was;
        cache.refresh(multi[e]);
      }
      changed = changed || rotation[e] != was;
    }
    if (!changed) break;
  }
  Id left = 0;
  for (std::uint64_t key : multi) left += cache.joins_twice(key) ? 1 : 0;
  return left;
}

// One pass of the rule over the flagged points: the pairings rotated, then
// every fan but a point's first given a new id (appended to `source`: the
// original point it copies). All is decided before a corner is rewritten,
// since the rule reads the other points' ids. Returns the edges left joined.
Id split_round(PointIndex* C, Id n, const Flagged& f, std::vector<PointIndex>& source) {
  std::vector<std::uint64_t> multi;
  std::vector<std::uint32_t> rotation;
  const FanRule fans{C, multi, rotation, {}, {}, {}};
  FanCache cache(fans, f, &multi);
  std::sort(multi.begin(), multi.end());
  rotation.assign(multi.size(), 0);
  const Id left = rotate_pairings(cache, rotation);
  std::vector<std::pair<std::uint32_t, PointIndex>> moves;  // corner, new id
  std::vector<PointIndex> id_of_root;
  for (std::size_t k = 0; k < f.size(); ++k) {
    const std::vector<std::uint32_t>& labels = cache.labels[k];
    id_of_root.assign(labels.size(), f.point[k]);
    const PointIndex original = Id{f.point[k]} < n ? f.point[k] : source[f.point[k] - n];
    for (std::size_t j = 1; j < labels.size(); ++j)
      if (labels[j] == j) {
        if (n + static_cast<Id>(source.size()) >= Id{std::numeric_limits<PointIndex>::max()})
          throw LimitError("split_nonmanifold: more than 2^32 - 1 points");
        id_of_root[j] = static_cast<PointIndex>(n + static_cast<Id>(source.size()));
        source.push_back(original);
      }
    for (std::size_t j = 1; j < labels.size(); ++j)
      if (labels[j] != 0) moves.emplace_back(f.list(k)[j], id_of_root[labels[j]]);
  }
  for (const auto& [corner, id] : moves) C[corner] = id;
  return left;
}

}  // namespace

NonmanifoldSplit split_nonmanifold(SurfaceMesh& mesh) {
  if (!mesh.all_triangles()) throw InputError("split_nonmanifold: the mesh has polygons; only triangles are split");
  const Id corners = static_cast<Id>(mesh.connectivity.size()), n = mesh.num_points();
  if (corners == 0) return {};
  if (corners > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("split_nonmanifold: more than 2^32 - 1 corners");
  PointIndex* C = mesh.connectivity.data();
  Flagged f = flag_points(C, corners, n);
  std::vector<PointIndex> source;  // the original point each new id copies
  NonmanifoldSplit result;
  // A split renames the corners around the points it splits, which can let
  // a rotation separate an edge it could not before: the points still
  // flagged are looked at again (a few rounds, each over them only).
  for (int round = 0; round < 4 && f.size() > 0; ++round) {
    const std::size_t added_before = source.size();
    result.edges_left = split_round(C, n, f, source);
    if (source.size() == added_before || result.edges_left == 0) break;
    f = reflag(C, f);
  }
  const Id added = static_cast<Id>(source.size());
  // Grown to their exact size (resize() would double the capacity).
  auto append_copies = [&](std::vector<float>& values, int k) {
    std::vector<float> grown;
    parallel::resize_fresh(grown, static_cast<std::size_t>((n + added) * k));
    parallel::for_each(n * k, [&](Id i) { grown[i] = values[i]; }, 1 << 16);
    for (Id i = 0; i < added; ++i) std::copy_n(values.begin() + Id{source[i]} * k, k, grown.begin() + (n + i) * k);
    values.swap(grown);
  };
  append_copies(mesh.points, 3);
  for (Field& field : mesh.point_fields) append_copies(field.values, field.components);
  result.points_added = added;
  return result;
}

}  // namespace keymesh::generate
