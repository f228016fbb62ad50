#include "keymesh/analyze/topology.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/core/free_storage.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/radix_sort.hpp"

namespace keymesh::analyze {

namespace {

// Lock-free union-find over point ids. Roots are always linked under the
// smaller index, so the final partition (and every count taken from it) is
// the same whatever order threads perform the unions in.
class ConcurrentUnionFind {
 public:
  explicit ConcurrentUnionFind(Id n) : parent_(static_cast<std::size_t>(n)) {
    parallel::for_each(n, [&](Id i) { parent_[i] = static_cast<std::uint32_t>(i); });
  }
  std::uint32_t find(std::uint32_t x) {
    for (;;) {
      std::uint32_t p = ref(x).load(std::memory_order_acquire);
      if (p == x) return x;
      const std::uint32_t gp = ref(p).load(std::memory_order_acquire);
      // Path halving: point x at its grandparent if nobody changed it meanwhile.
      if (gp != p) ref(x).compare_exchange_weak(p, gp, std::memory_order_acq_rel, std::memory_order_relaxed);
      x = gp;
    }
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    for (;;) {
      a = find(a);
      b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);
      std::uint32_t expected = a;  // a must still be a root when it is linked
      if (ref(a).compare_exchange_strong(expected, b, std::memory_order_acq_rel, std::memory_order_relaxed)) return;
    }
  }

 private:
  std::atomic_ref<std::uint32_t> ref(std::uint32_t i) { return std::atomic_ref<std::uint32_t>(parent_[i]); }
  std::vector<std::uint32_t> parent_;
};

// One neighbour entry of a vertex's fan: the point across an edge, the cell
// that edge belongs to and the local corner slot (for the local union-find).
struct FanEntry {
  std::uint64_t key;    // neighbour point << 32 | cell
  std::uint32_t local;
};

// Insertion sort for the short lists of a point's fan (typically 6 to 12
// entries); std::sort only for the rare high-valence point.
template <class T, class Less>
void small_sort(T* first, T* last, Less less) {
  if (last - first > 32) {
    std::sort(first, last, less);
    return;
  }
  for (T* i = first + 1; i < last; ++i) {
    T x = *i;
    T* j = i;
    for (; j > first && less(x, *(j - 1)); --j) *j = *(j - 1);
    *j = x;
  }
}

std::uint32_t local_find(std::uint32_t* parent, std::uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

void local_unite(std::uint32_t* parent, std::uint32_t a, std::uint32_t b) {
  a = local_find(parent, a);
  b = local_find(parent, b);
  if (a != b) parent[std::max(a, b)] = std::min(a, b);
}

// Maps a float to an unsigned integer with the same order (and -0 to +0), so
// equal floats get equal keys.
std::uint32_t sortable_bits(float f) {
  if (f == 0.0f) f = 0.0f;
  const std::uint32_t u = std::bit_cast<std::uint32_t>(f);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

// Points whose position equals (float ==) an earlier point's. One radix sort
// by x groups candidates; the short runs of equal x are then sorted by (y, z)
// and neighbours compared. Cheaper than a full lexicographic weld.
Id count_duplicate_points(const float* xyz, Id n) {
  if (n < 2) return 0;
  std::vector<std::uint32_t> keys(static_cast<std::size_t>(n)), perm(static_cast<std::size_t>(n));
  parallel::for_each(n, [&](Id i) {
    keys[i] = sortable_bits(xyz[3 * i]);
    perm[i] = static_cast<std::uint32_t>(i);
  });
  parallel::sort_pairs(keys, perm, 32);
  // Runs of equal x, found per fixed chunk (a run crossing a chunk boundary
  // is owned by the chunk where it starts).
  const int chunks = parallel::chunk_count(n, 1 << 15);
  std::vector<Id> dups(std::max(chunks, 1), 0);
  parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
    Id i = b;
    while (i > 0 && i < n && keys[i] == keys[i - 1]) ++i;  // run started in the previous chunk
    while (i < e) {
      Id j = i + 1;
      while (j < n && keys[j] == keys[i]) ++j;
      if (j - i > 1) {
        std::uint32_t* run = perm.data() + i;
        auto yz = [&](std::uint32_t p) {
          return (std::uint64_t{sortable_bits(xyz[3 * Id{p} + 1])} << 32) | sortable_bits(xyz[3 * Id{p} + 2]);
        };
        std::sort(run, run + (j - i), [&](std::uint32_t a, std::uint32_t bb) { return yz(a) < yz(bb); });
        for (Id k = 1; k < j - i; ++k) {
          const float* p = xyz + 3 * Id{run[k]};
          const float* q = xyz + 3 * Id{run[k - 1]};
          if (p[0] == q[0] && p[1] == q[1] && p[2] == q[2]) ++dups[c];  // NaN never equals
        }
      }
      i = j;
    }
  });
  Id total = 0;
  for (Id d : dups) total += d;
  return total;
}

struct ChunkCounts {
  Id edges = 0, boundary = 0, nonmanifold_edges = 0, nonmanifold_vertices = 0, unused = 0;
};

// Offsets, sizes and point ids a report can trust; the first out-of-range
// id whatever the thread count.
void check_layout(const SurfaceMesh& mesh) {
  if (mesh.points.size() % 3 != 0)
    throw InputError("check_topology: " + std::to_string(mesh.points.size()) + " point coordinates, not a multiple of 3");
  const Id n = mesh.num_points();
  const auto& conn = mesh.connectivity;
  const Id corners = static_cast<Id>(conn.size());
  if (mesh.offsets.empty()) {
    if (corners % 3 != 0)
      throw InputError("check_topology: triangle connectivity size " + std::to_string(corners) + " is not a multiple of 3");
  } else {
    if (mesh.offsets.front() != 0 || mesh.offsets.back() != conn.size())
      throw InputError("check_topology: cell offsets do not span the connectivity");
    for (std::size_t c = 0; c + 1 < mesh.offsets.size(); ++c)
      if (mesh.offsets[c + 1] < mesh.offsets[c])
        throw InputError("check_topology: cell offsets decrease at cell " + std::to_string(c));
  }
  const Id m = mesh.num_cells();
  if (n > Id{std::numeric_limits<std::uint32_t>::max()} || corners > Id{std::numeric_limits<std::uint32_t>::max()} ||
      m > Id{std::numeric_limits<std::uint32_t>::max()})
    throw LimitError("check_topology: more than 2^32 - 1 points, cells or cell corners");
  const int chunks = parallel::chunk_count(corners, 1 << 16);
  std::vector<Id> first_bad(std::max(chunks, 1), corners);
  parallel::for_each_chunk(corners, chunks, [&](Id b, Id e, int c) {
    for (Id i = b; i < e; ++i)
      if (Id{conn[i]} >= n) {
        first_bad[c] = i;
        break;
      }
  });
  const Id bad = *std::min_element(first_bad.begin(), first_bad.end());
  if (bad < corners)
    throw InputError("check_topology: cell point id " + std::to_string(conn[bad]) + " out of range (" +
                     std::to_string(n) + " points)");
}

// Corners grouped by point (CSR: point v's corners are order[start[v] ..
// start[v + 1])). Filled with atomic cursors, so the order inside a point's
// list depends on scheduling; the fan pass sorts each list by corner index
// first, which makes everything after it deterministic.
void corners_by_point(const SurfaceMesh& mesh, std::vector<Id>& start, std::vector<std::uint32_t>& order) {
  const Id n = mesh.num_points();
  const auto& conn = mesh.connectivity;
  const Id corners = static_cast<Id>(conn.size());
  start.assign(static_cast<std::size_t>(n) + 1, 0);
  order.resize(static_cast<std::size_t>(corners));
  std::vector<std::uint32_t> cursor(static_cast<std::size_t>(n), 0);
  parallel::for_each(corners, [&](Id i) {
    std::atomic_ref<std::uint32_t>(cursor[conn[i]]).fetch_add(1, std::memory_order_relaxed);
  });
  for (Id v = 0; v < n; ++v) start[v + 1] = start[v] + cursor[v];
  parallel::for_each(n, [&](Id v) { cursor[v] = 0; });
  parallel::for_each(corners, [&](Id i) {
    const PointIndex v = conn[i];
    const std::uint32_t slot = std::atomic_ref<std::uint32_t>(cursor[v]).fetch_add(1, std::memory_order_relaxed);
    order[start[v] + slot] = static_cast<std::uint32_t>(i);
  });
}

// The fan of point v (its d corners at list): every edge from v is counted
// at its smaller end point, with how many cells use it; the corners are
// united through shared edges and repeated cells, and more than one class
// makes v non-manifold. `ent` and `par` are scratch for 2d and d entries.
struct FanPass {
  const SurfaceMesh& mesh;
  const std::vector<std::uint32_t>& corner_cell;  // empty for triangles
  std::vector<std::uint8_t>& degenerate;

  // The cell of a corner and the corners before and after it in the cell.
  void neighbours(Id corner, Id& c, Id& prev, Id& next) const {
    if (corner_cell.empty()) {
      c = corner / 3;
      const Id b = 3 * c;
      const Id at = corner - b;
      prev = b + (at == 0 ? 2 : at - 1);
      next = b + (at == 2 ? 0 : at + 1);
    } else {
      c = corner_cell[corner];
      const Id b = static_cast<Id>(mesh.offsets[c]);
      const Id e = static_cast<Id>(mesh.offsets[c + 1]);
      prev = corner == b ? e - 1 : corner - 1;
      next = corner + 1 == e ? b : corner + 1;
    }
  }

  void operator()(Id v, std::uint32_t* list, Id d, FanEntry* ent, std::uint32_t* par, ChunkCounts& cc) const {
    const auto& conn = mesh.connectivity;
    small_sort(list, list + d, [](std::uint32_t a, std::uint32_t b) { return a < b; });
    Id ne = 0;
    Id prev_cell = -1;
    for (Id j = 0; j < d; ++j) {
      Id c, prev, next;
      neighbours(list[j], c, prev, next);
      const auto lj = static_cast<std::uint32_t>(j);
      par[j] = lj;
      const auto cell_bits = static_cast<std::uint64_t>(c);
      ent[ne++] = {(std::uint64_t{conn[prev]} << 32) | cell_bits, lj};
      ent[ne++] = {(std::uint64_t{conn[next]} << 32) | cell_bits, lj};
      // Two corners of one cell at the same point: the cell repeats an id.
      if (c == prev_cell) {
        std::atomic_ref<std::uint8_t>(degenerate[c]).store(1, std::memory_order_relaxed);
        local_unite(par, lj, lj - 1);
      }
      prev_cell = c;
    }
    small_sort(ent, ent + ne, [](const FanEntry& a, const FanEntry& b) { return a.key < b.key; });
    for (Id g = 0; g < ne;) {
      const std::uint64_t w = ent[g].key >> 32;
      Id h = g + 1;
      Id distinct = 1;
      for (; h < ne && (ent[h].key >> 32) == w; ++h) {
        if (ent[h].key != ent[h - 1].key) ++distinct;
        local_unite(par, ent[g].local, ent[h].local);
      }
      // An edge from v to itself only marks a degenerate cell (already flagged).
      if (w > static_cast<std::uint64_t>(v)) {
        ++cc.edges;
        if (distinct == 1) ++cc.boundary;
        if (distinct >= 3) ++cc.nonmanifold_edges;
      }
      g = h;
    }
    Id fans = 0;
    for (Id j = 0; j < d; ++j)
      if (local_find(par, static_cast<std::uint32_t>(j)) == j) ++fans;
    if (fans > 1) ++cc.nonmanifold_vertices;
  }
};

// Every point's fan, in fixed chunks; the counts summed into r.
void count_fans(const SurfaceMesh& mesh, const FanPass& fan, const std::vector<Id>& start,
                std::vector<std::uint32_t>& order, TopologyReport& r) {
  const Id n = mesh.num_points();
  Id max_degree = 0;
  for (Id v = 0; v < n; ++v) max_degree = std::max(max_degree, start[v + 1] - start[v]);
  const int chunks = parallel::chunk_count(n, 1 << 12);
  std::vector<ChunkCounts> counts(std::max(chunks, 1));
  // Per-chunk scratch, padded apart by a few cache lines: threads writing
  // neighbouring bytes would otherwise ping-pong the lines between cores.
  const Id entry_stride = 2 * max_degree + 16;
  const Id parent_stride = max_degree + 64;
  std::vector<FanEntry> entries(static_cast<std::size_t>(std::max(chunks, 1) * entry_stride));
  std::vector<std::uint32_t> parents(static_cast<std::size_t>(std::max(chunks, 1) * parent_stride));
  parallel::for_each_chunk(n, chunks, [&](Id vb, Id ve, int chunk) {
    ChunkCounts cc;  // local: counts[] entries share cache lines
    for (Id v = vb; v < ve; ++v) {
      const Id s = start[v], d = start[v + 1] - s;
      if (d == 0) {
        ++cc.unused;
        continue;
      }
      fan(v, order.data() + s, d, entries.data() + chunk * entry_stride, parents.data() + chunk * parent_stride, cc);
    }
    counts[chunk] = cc;
  });
  for (const ChunkCounts& cc : counts) {
    r.edges += cc.edges;
    r.boundary_edges += cc.boundary;
    r.nonmanifold_edges += cc.nonmanifold_edges;
    r.nonmanifold_vertices += cc.nonmanifold_vertices;
    r.unused_points += cc.unused;
  }
}

// Components: cells joined through shared points (points no cell uses are
// not components).
Id count_components(const SurfaceMesh& mesh, const std::vector<Id>& start) {
  const Id n = mesh.num_points();
  const auto& conn = mesh.connectivity;
  ConcurrentUnionFind uf(n);
  parallel::for_each(mesh.num_cells(), [&](Id c) {
    const std::uint64_t b = mesh.cell_begin(c), e = mesh.cell_end(c);
    for (std::uint64_t k = b + 1; k < e; ++k) uf.unite(conn[b], conn[k]);
  }, 1 << 14);
  const int rc = parallel::chunk_count(n, 1 << 14);
  std::vector<Id> roots(std::max(rc, 1), 0);
  parallel::for_each_chunk(n, rc, [&](Id b, Id e, int c) {
    for (Id v = b; v < e; ++v)
      if (start[v + 1] > start[v] && uf.find(static_cast<std::uint32_t>(v)) == v) ++roots[c];
  });
  Id total = 0;
  for (Id x : roots) total += x;
  return total;
}

}  // namespace

namespace {
// check_fans' counts; `start` keeps the corners' grouping by point.
TopologyReport fans_of(const SurfaceMesh& mesh, std::vector<Id>& start) {
  check_layout(mesh);
  TopologyReport r;
  const Id m = mesh.num_cells();
  r.points = mesh.num_points();
  r.cells = m;
  // Cell of every corner (implicit for triangles).
  std::vector<std::uint32_t> corner_cell;
  std::vector<std::uint8_t> degenerate(static_cast<std::size_t>(m), 0);
  if (!mesh.offsets.empty()) {
    corner_cell.resize(mesh.connectivity.size());
    parallel::for_each(m, [&](Id c) {
      const std::uint64_t b = mesh.offsets[c], e = mesh.offsets[c + 1];
      for (std::uint64_t k = b; k < e; ++k) corner_cell[k] = static_cast<std::uint32_t>(c);
      if (e - b < 3) degenerate[c] = 1;  // fewer than three points spans no area
    }, 1024);
  }
  std::vector<std::uint32_t> order;
  corners_by_point(mesh, start, order);
  count_fans(mesh, FanPass{mesh, corner_cell, degenerate}, start, order, r);
  free_storage(order);
  for (std::uint8_t f : degenerate) r.degenerate_cells += f;
  return r;
}
}  // namespace

TopologyReport check_fans(const SurfaceMesh& mesh) {
  std::vector<Id> start;
  return fans_of(mesh, start);
}

TopologyReport check_topology(const SurfaceMesh& mesh) {
  std::vector<Id> start;
  TopologyReport r = fans_of(mesh, start);
  const Id n = mesh.num_points(), m = mesh.num_cells();
  r.components = count_components(mesh, start);
  r.duplicate_points = count_duplicate_points(mesh.points.data(), n);
  const Id used = n - r.unused_points;
  r.euler_characteristic = used - r.edges + m;
  r.closed_manifold = m > 0 && r.boundary_edges == 0 && r.nonmanifold_edges == 0 && r.nonmanifold_vertices == 0 &&
                      r.degenerate_cells == 0;
  return r;
}

}  // namespace keymesh::analyze
