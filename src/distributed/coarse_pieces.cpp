// The coarsened contour in pieces (keymesh/distributed/coarse_pieces.hpp).
// Built on contour_layers, number_keys (through own_piece) and
// all_gather_bytes, so it compiles without MPI too (where those refuse).
#include "keymesh/distributed/coarse_pieces.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "keymesh/analyze/topology.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/distributed/contour_distributed.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/generate/coarsen/coarsen.hpp"
#include "keymesh/mesh/normals.hpp"
#include "keymesh/mesh/unused_points.hpp"

namespace keymesh::distributed {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The volume's layout as the coarse keys read it (isovalue * nxyz + grid point).
struct Grid {
  std::uint64_t nxy = 0, nxyz = 0;
  Id layers = 0;  // voxel layers: nz - 1
  Id plane(std::uint64_t coarse_key) const { return static_cast<Id>(coarse_key % nxyz / nxy); }
};

// Collective: the sums over all ranks of two counts.
std::array<long long, 2> summed(long long a, long long b) {
  std::vector<std::byte> mine(2 * sizeof(long long));
  std::memcpy(mine.data(), &a, sizeof a);
  std::memcpy(mine.data() + sizeof a, &b, sizeof b);
  std::array<long long, 2> sum{0, 0};
  for (const auto& bytes : all_gather_bytes(mine)) {
    long long x[2];
    std::memcpy(x, bytes.data(), sizeof x);
    sum[0] += x[0], sum[1] += x[1];
  }
  return sum;
}

// A fine triangle's voxel layer: its corners' lowest edge-key plane (every
// marching cubes triangle has a corner on its voxel's bottom face or on a z
// edge from it; generate/contour/layer_blocks.cpp).
std::vector<float> fine_layers(const FineLayers& f, const Grid& g) {
  const std::uint64_t per_iso = 3 * g.nxyz;
  std::vector<float> layer(static_cast<std::size_t>(f.mesh.num_cells()));
  const PointIndex* C = f.mesh.connectivity.data();
  for (Id t = 0; t < f.mesh.num_cells(); ++t) {
    std::uint64_t plane = ~std::uint64_t{0};
    for (int c = 0; c < 3; ++c) plane = std::min(plane, f.keys[C[3 * t + c]] % per_iso / 3 / g.nxy);
    layer[static_cast<std::size_t>(t)] = static_cast<float>(plane);  // exact below 2^24 layers (checked)
  }
  return layer;
}

// The coarse mesh of one attempt, before its unused points are removed:
// every point's original (a copy's is the point it copies) and that
// original's coarse key, and each triangle's fine voxel layer.
struct CoarseLayers {
  SurfaceMesh mesh;
  generate::NonmanifoldSplit split;
  std::vector<std::uint64_t> key;      // per original point
  std::vector<PointIndex> original;    // per point
  std::vector<float> layer;            // per triangle
  Id originals = 0;
  Id own_fine_triangles = 0;           // of the fine layers: those of the rank's own layers
};

// The fine layers coarsened as one process coarsens them, with the split's
// rounds agreed with the other ranks (the copies and edges left counted at
// the points this rank owns). Collective: an error here ends every rank.
CoarseLayers coarsen_layers(FineLayers& fine, const Grid& g, std::uint64_t key_range, std::pair<Id, Id> own,
                            std::pair<Id, Id> own_layers) {
  CoarseLayers c;
  c.key = fine.nearest;
  std::sort(c.key.begin(), c.key.end());
  c.key.erase(std::unique(c.key.begin(), c.key.end()), c.key.end());
  fine.mesh.cell_fields.push_back(Field{"fine_layer", 1, {}});
  const std::vector<float> layers = fine_layers(fine, g);
  fine.mesh.cell_fields.back().values.assign(layers.begin(), layers.end());
  for (float layer : layers)
    c.own_fine_triangles += own_layers.first <= static_cast<Id>(layer) && static_cast<Id>(layer) < own_layers.second;
  const generate::SplitRounds rounds{
      [&](PointIndex p) {
        const Id z = g.plane(c.key[p]);
        return own.first <= z && z < own.second;
      },
      [](Id added, Id left) {
        const auto sum = summed(added, left);
        return sum[0] > 0 && sum[1] > 0;
      }};
  try {
    c.mesh = generate::coarsen_part(fine.mesh, fine.nearest, key_range, rounds, c.split);
  } catch (const std::exception& e) {
    // Inside the rounds' agreements: the others may wait for this rank.
    std::fprintf(stderr, "keymesh: rank %d: coarsening: %s\n", rank(), e.what());
    abort_all(1);
  }
  fine.mesh.cell_fields.pop_back();
  c.layer.assign(c.mesh.cell_fields.back().values.begin(), c.mesh.cell_fields.back().values.end());
  c.mesh.cell_fields.pop_back();
  c.originals = c.mesh.num_points() - static_cast<Id>(c.split.split_from.size());
  if (c.originals != static_cast<Id>(c.key.size()))
    throw InputError("distributed coarsening: " + std::to_string(c.originals) + " coarse points for " +
                     std::to_string(c.key.size()) + " grid points (internal error)");
  c.original.resize(static_cast<std::size_t>(c.mesh.num_points()));
  std::iota(c.original.begin(), c.original.begin() + c.originals, PointIndex{0});
  for (std::size_t i = 0; i < c.split.split_from.size(); ++i)
    c.original[static_cast<std::size_t>(c.originals) + i] = c.original[c.split.split_from[i]];
  return c;
}

// Which triangles this rank writes (1 its own: made by its layers, 2 a ghost
// cell: another that uses a point of its own) and which points it needs
// exactly: those of the written triangles and those it owns.
struct Written {
  std::vector<std::uint8_t> face, needed;
};

Written written(const CoarseLayers& c, const Grid& g, std::pair<Id, Id> layers, std::pair<Id, Id> own) {
  const SurfaceMesh& m = c.mesh;
  Written w;
  w.face.assign(static_cast<std::size_t>(m.num_cells()), 0);
  w.needed.assign(static_cast<std::size_t>(m.num_points()), 0);
  std::vector<std::uint8_t> mine(w.needed.size(), 0);
  const PointIndex* C = m.connectivity.data();
  for (Id t = 0; t < m.num_cells(); ++t) {
    const auto layer = static_cast<Id>(c.layer[static_cast<std::size_t>(t)]);
    if (layer < layers.first || layer >= layers.second) continue;
    w.face[static_cast<std::size_t>(t)] = 1;
    for (int k = 0; k < 3; ++k) mine[C[3 * t + k]] = 1;
  }
  for (Id t = 0; t < m.num_cells(); ++t) {
    auto& f = w.face[static_cast<std::size_t>(t)];
    if (!f && (mine[C[3 * t]] || mine[C[3 * t + 1]] || mine[C[3 * t + 2]])) f = 2;
    if (f)
      for (int k = 0; k < 3; ++k) w.needed[C[3 * t + k]] = 1;
  }
  for (std::size_t p = 0; p < w.needed.size(); ++p) {
    const Id z = g.plane(c.key[c.original[p]]);
    w.needed[p] = w.needed[p] || (own.first <= z && z < own.second);
  }
  return w;
}

// The coarse mesh's edges between originals (a copy's corner read as the
// point it copies): each once, and those with more than two triangles (the
// split's multi-edges are among them).
struct OriginalEdges {
  std::vector<std::uint64_t> all, multi;  // min << 32 | max
  explicit OriginalEdges(const CoarseLayers& c) {
    const PointIndex* C = c.mesh.connectivity.data();
    std::vector<std::uint64_t> e;
    e.reserve(static_cast<std::size_t>(3 * c.mesh.num_cells()));
    for (Id t = 0; t < c.mesh.num_cells(); ++t)
      for (int k = 0; k < 3; ++k) {
        const PointIndex a = c.original[C[3 * t + k]], b = c.original[C[3 * t + (k + 1) % 3]];
        if (a != b) e.push_back(std::uint64_t{std::min(a, b)} << 32 | std::max(a, b));
      }
    std::sort(e.begin(), e.end());
    for (std::size_t i = 0; i < e.size();) {
      std::size_t j = i;
      while (j < e.size() && e[j] == e[i]) ++j;
      all.push_back(e[i]);
      if (j - i > 2) multi.push_back(e[i]);
      i = j;
    }
  }
};

// Whether this rank's mesh holds the one process's result at every point
// it needs. A coarse point's position, triangles, folds and whether it is
// one closed fan read the voxel layers touching it: all are exact one plane
// inside a cut side of the contoured layers, and its normal (its neighbours
// one plane further) two planes inside. What the split does is inexact
// first on the cut planes, then spreads: within a round along multi-edges
// (the sweeps' rotations couple their ends), and from one round to the next
// from a point that may have split to the points around it that the rule
// looks at (it reads their ends' ids). `rounds`: how many the split ran.
bool decisions_inside(const CoarseLayers& c, const Grid& g, const Written& w, Id first, Id end) {
  const auto n = static_cast<std::size_t>(c.originals);
  auto cut_plane = [&](Id z) { return (first > 0 && z == first) || (end < g.layers && z == end); };
  auto near_cut = [&](Id z) { return (first > 0 && z <= first + 1) || (end < g.layers && z >= end - 1); };
  std::vector<std::uint8_t> flagged(n, 0), inexact(n, 0);
  for (PointIndex p : c.split.first_flagged) flagged[p] = 1;
  for (std::size_t p = 0; p < n; ++p) inexact[p] = cut_plane(g.plane(c.key[p]));
  const OriginalEdges edges(c);
  std::vector<PointIndex> parent(n);  // components joined by the multi-edges
  std::iota(parent.begin(), parent.end(), PointIndex{0});
  auto find = [&](PointIndex x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::uint64_t e : edges.multi) parent[find(static_cast<PointIndex>(e >> 32))] = find(static_cast<PointIndex>(e));
  auto spread_along_multi_edges = [&] {
    std::vector<std::uint8_t> reached(n, 0);
    for (std::size_t p = 0; p < n; ++p) reached[find(static_cast<PointIndex>(p))] |= inexact[p];
    for (std::size_t p = 0; p < n; ++p) inexact[p] |= reached[find(static_cast<PointIndex>(p))];
  };
  spread_along_multi_edges();
  for (int round = 1; round < c.split.rounds; ++round) {
    std::vector<std::uint8_t> next = inexact;
    for (std::uint64_t e : edges.all) {
      const auto a = static_cast<PointIndex>(e >> 32), b = static_cast<PointIndex>(e);
      next[b] = static_cast<std::uint8_t>(next[b] | (inexact[a] & flagged[b]));
      next[a] = static_cast<std::uint8_t>(next[a] | (inexact[b] & flagged[a]));
    }
    inexact.swap(next);
    spread_along_multi_edges();
  }
  for (std::size_t p = 0; p < w.needed.size(); ++p) {
    const PointIndex o = c.original[p];
    if (w.needed[p] && (near_cut(g.plane(c.key[o])) || inexact[o])) return false;
  }
  return true;
}

// The copies' place in the one process's order. The split appends a
// round's copies in the order of the points it looks at, and those are the
// points still odd in the order they were looked at before, then the last
// round's copies: so a copy's place is set by the rounds that made it and
// its forebears (its chain: a subset of the rounds before its own), then by
// its original's key, then by its place among that original's copies. The
// chains in that order (round, then the forebears' rounds from the latest);
// 0 is the originals'.
int chain_index(int round, unsigned forebears) {
  static const std::vector<std::pair<int, std::vector<int>>> order = [] {
    std::vector<std::pair<int, std::vector<int>>> all;
    for (int r = 1; r <= 4; ++r)
      for (unsigned m = 0; m < (1u << r); m += 2) {  // bits 1 .. r - 1: the forebears' rounds
        std::vector<int> latest_first;
        for (int c = r - 1; c >= 1; --c)
          if (m >> c & 1) latest_first.push_back(c);
        latest_first.push_back(0);
        all.push_back({r, latest_first});
      }
    std::sort(all.begin(), all.end());
    return all;
  }();
  std::vector<int> latest_first;
  for (int c = round - 1; c >= 1; --c)
    if (forebears >> c & 1) latest_first.push_back(c);
  latest_first.push_back(0);
  const auto it = std::find(order.begin(), order.end(), std::pair<int, std::vector<int>>{round, latest_first});
  return 1 + static_cast<int>(it - order.begin());
}
constexpr int kChains = 16;  // the originals and 15 chains of at most four rounds

// Every point's key for the distributed KEY-REDUCE (halo_piece.hpp's
// order_key: segment << kSegmentShift | key): segment = chain * isovalues +
// isovalue, key = grid point << bits | place among its original's copies
// (0: the original). Ascending in the one process's order.
std::vector<std::uint64_t> order_keys(const CoarseLayers& c, const Grid& g, Id isovalues) {
  const int bits = kSegmentShift - static_cast<int>(std::bit_width(g.nxyz - 1));
  if (bits < 1 || kChains * isovalues >= (Id{1} << (63 - kSegmentShift)))
    throw LimitError("distributed coarsening: " + std::to_string(g.nxyz) + " grid points and " +
                     std::to_string(isovalues) + " isovalues exceed the pieces' 2^47 keys per segment");
  const auto copies = c.split.split_from.size();
  std::vector<unsigned> forebears(copies, 0);
  std::vector<std::uint32_t> made(static_cast<std::size_t>(c.originals), 0);
  std::vector<std::uint64_t> out(static_cast<std::size_t>(c.mesh.num_points()));
  for (std::size_t p = 0; p < out.size(); ++p) {
    const std::uint64_t key = c.key[c.original[p]];
    std::uint64_t place = 0;
    int chain = 0;
    if (p >= static_cast<std::size_t>(c.originals)) {
      const std::size_t i = p - static_cast<std::size_t>(c.originals);
      const PointIndex from = c.split.split_from[i];
      if (Id{from} >= c.originals) {
        const std::size_t j = from - static_cast<std::size_t>(c.originals);
        forebears[i] = forebears[j] | 1u << c.split.copy_round[j];
      }
      chain = chain_index(c.split.copy_round[i], forebears[i]);
      place = ++made[c.original[p]];
      if (place >> bits)
        throw LimitError("distributed coarsening: " + std::to_string(place) + " copies of one point exceed the " +
                         "pieces' keys");
    }
    const auto segment = static_cast<std::uint64_t>(chain) * static_cast<std::uint64_t>(isovalues) + key / g.nxyz;
    out[p] = segment << kSegmentShift | (key % g.nxyz) << bits | place;
  }
  for (std::size_t p = 1; p < out.size(); ++p)
    if (out[p] <= out[p - 1])
      throw InputError("distributed coarsening: the copies' keys do not follow their order (internal error)");
  return out;
}

// What the rank keeps once its halo passed: the points without a triangle
// removed, averaged normals summed over the coarse triangles, and the
// marks own_piece reads.
struct Finished {
  std::vector<std::uint64_t> order_key;
  std::vector<Id> row;
  std::vector<std::uint8_t> ghost_face;
  std::vector<std::uint32_t> own_isovalue;  // per own triangle, in order
};

Finished finish(CoarseLayers& c, const Written& w, const Grid& g, Id isovalues, bool average) {
  Finished f;
  const std::vector<std::uint64_t> keys = order_keys(c, g, isovalues);
  std::vector<std::uint8_t> unused(keys.size(), 0);
  for (PointIndex p : c.split.unused) unused[p] = 1;
  for (std::size_t p = 0; p < keys.size(); ++p)
    if (!unused[p]) {
      f.order_key.push_back(keys[p]);
      f.row.push_back(g.plane(c.key[c.original[p]]));
    }
  const PointIndex* C = c.mesh.connectivity.data();
  for (std::size_t t = 0; t < w.face.size(); ++t)
    if (w.face[t] == 1) f.own_isovalue.push_back(static_cast<std::uint32_t>(c.key[c.original[C[3 * t]]] / g.nxyz));
  remove_points(c.mesh, c.split.unused);
  for (std::uint8_t face : w.face) f.ghost_face.push_back(face == 1 ? 0 : 1);
  if (average) average_normals(c.mesh);
  return f;
}

// The share of check_fans' counts at the points this rank owns.
void count_owned(CoarsePiece& out, const SurfaceMesh& mesh, const std::vector<Id>& row, std::pair<Id, Id> own) {
  std::vector<std::uint8_t> owned(row.size());
  for (std::size_t p = 0; p < row.size(); ++p) owned[p] = own.first <= row[p] && row[p] < own.second;
  const analyze::TopologyReport t = analyze::check_fans(mesh, owned);
  out.nonmanifold_edges = t.nonmanifold_edges;
  out.nonmanifold_vertices = t.nonmanifold_vertices;
  out.boundary_edges = t.boundary_edges;
}

}  // namespace

CoarsePiece coarse_piece(PlaneSource& source, const generate::ContourOptions& options, bool balance,
                         std::size_t memory_limit) {
  const ImageGrid& head = source.header();
  const int P = size(), r = rank();
  require_distributable(head, options, P);
  const Id nz = head.dims[2], isovalues = static_cast<Id>(options.isovalues.size());
  const Grid g{static_cast<std::uint64_t>(head.dims[0] * head.dims[1]),
               static_cast<std::uint64_t>(head.dims[0] * head.dims[1] * nz), nz - 1};
  if (g.layers >= (Id{1} << 24)) throw LimitError("distributed coarsening: more than 2^24 voxel layers");
  const std::vector<Id> bounds = slab_bounds(source, options, balance);
  const Id lo = bounds[static_cast<std::size_t>(r)], hi = bounds[static_cast<std::size_t>(r) + 1];
  const std::pair<Id, Id> own{lo, r + 1 == P ? nz : hi};  // planes: the last rank's ends with the top
  CoarsePiece out;
  out.first_layer = lo;
  out.layers = hi - lo;
  const bool average = options.normals == generate::ContourNormals::Average;
  for (Id h = kFirstCoarseHalo;; h *= 2) {
    ++out.attempts;
    out.halo_layers = h;
    const Id first = std::max<Id>(0, lo - h), end = std::min(g.layers, hi + h);
    FineLayers fine;
    agreed([&] { fine = contour_layers(source, options, first, end, memory_limit); });
    out.slabs += fine.slabs;
    out.fine_points_held = std::max(out.fine_points_held, fine.mesh.num_points());
    out.read += fine.read;
    out.contour += fine.contour;
    auto t0 = Clock::now();
    CoarseLayers c = coarsen_layers(fine, g, g.nxyz * static_cast<std::uint64_t>(isovalues), own, {lo, hi});
    fine = FineLayers{};  // the fine layers are not read again
    Written w;
    bool inside = false;
    agreed([&] {
      w = written(c, g, {lo, hi}, own);
      inside = decisions_inside(c, g, w, first, end);
      out.triangles_before = c.own_fine_triangles;
    });
    out.coarsen += seconds_since(t0);
    if (!all_ok(inside)) continue;
    t0 = Clock::now();
    Finished f;
    agreed([&] {
      f = finish(c, w, g, isovalues, average);
      count_owned(out, c.mesh, f.row, own);
    });
    out.piece = own_piece({c.mesh, f.ghost_face, f.order_key, f.row, static_cast<int>(kChains * isovalues)}, own);
    out.own_isovalue = std::move(f.own_isovalue);
    out.number = seconds_since(t0);
    return out;
  }
}

}  // namespace keymesh::distributed
