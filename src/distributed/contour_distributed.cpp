// Distributed contouring over MPI (keymesh/distributed/contour_distributed.hpp).
#include "keymesh/distributed/contour_distributed.hpp"

#if defined(KEYMESH_HAVE_MPI)

#include "mpi_library.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <unordered_map>

#include "keymesh/core/error.hpp"
#include "keymesh/core/free_storage.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/generate/contour/contour_stream.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/mesh/normals.hpp"

namespace keymesh::distributed {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

int checked_int(long long n, const char* what) {
  if (n < 0 || n > std::numeric_limits<int>::max())
    throw LimitError(std::string("distributed contour: ") + what + " exceed MPI's 2^31 - 1 elements per message");
  return static_cast<int>(n);
}

// Gathers per-rank arrays packed segment after segment (count[q * S + s]
// elements of `per` values from rank q for segment s) to rank 0, reordered
// segment-major, rank order within a segment.
template <class T, class A>
void gather_segments(const std::vector<T>& local, int per, MPI_Datatype type, const std::vector<long long>& count,
                     int segments, std::vector<T, A>& out) {
  int P = 1, r = 0;
  mpi().Comm_size(mpi().comm_world, &P);
  mpi().Comm_rank(mpi().comm_world, &r);
  std::vector<int> sizes(static_cast<std::size_t>(P)), displs(static_cast<std::size_t>(P));
  long long all = 0;
  for (int q = 0; q < P; ++q) {
    long long rank_total = 0;
    for (int s = 0; s < segments; ++s) rank_total += count[static_cast<std::size_t>(q) * segments + s];
    sizes[q] = checked_int(rank_total * per, "gathered arrays");
    displs[q] = checked_int(all * per, "gathered arrays");
    all += rank_total;
  }
  checked_int(all * per, "gathered arrays");
  std::vector<T> packed(r == 0 ? static_cast<std::size_t>(all * per) : 0);
  mpi().Gatherv(local.data(), checked_int(static_cast<long long>(local.size()), "gathered arrays"), type, packed.data(),
                sizes.data(), displs.data(), type, 0, mpi().comm_world);
  if (r != 0) return;
  std::vector<long long> dst_first(static_cast<std::size_t>(segments) * P);
  long long at = 0;
  for (int s = 0; s < segments; ++s)
    for (int q = 0; q < P; ++q) {
      dst_first[static_cast<std::size_t>(s) * P + q] = at;
      at += count[static_cast<std::size_t>(q) * segments + s];
    }
  out.resize(static_cast<std::size_t>(all * per));
  long long src = 0;
  for (int q = 0; q < P; ++q)
    for (int s = 0; s < segments; ++s) {
      const long long c = count[static_cast<std::size_t>(q) * segments + s];
      std::copy_n(packed.begin() + src * per, c * per, out.begin() + dst_first[static_cast<std::size_t>(s) * P + q] * per);
      src += c;
    }
}

}  // namespace

void require_distributable(const ImageGrid& head, const generate::ContourOptions& options, int ranks) {
  if (options.weld == generate::ContourWeld::VertexWeld)
    throw InputError("distributed contour: --weld vertexweld compares coordinates; across ranks only keys weld");
  if (options.backend != generate::Backend::Cpu) throw InputError("distributed contour: --backend cpu only so far");
  if (options.history && options.coarsen)
    throw InputError("distributed contour: --history with --coarsen: a coarsened point has no one edge and t");
  if (head.dims[2] - 1 < ranks)
    throw InputError("distributed contour: " + std::to_string(head.dims[2] - 1) + " voxel layers (z) for " +
                     std::to_string(ranks) + " ranks; each rank needs at least one (use fewer ranks)");
}

namespace {

// Layer boundaries that split the work evenly: layer k weighs its triangles
// plus the classification of its samples (about a hundredth of a triangle's
// cost each, measured: 512^3 classify ~0.2 ns/sample, the rest ~25 ns per
// triangle). Every rank computes the same bounds from the same counts.
std::vector<Id> balanced_bounds(const std::vector<long long>& triangles, Id nxy, int P) {
  const Id L = static_cast<Id>(triangles.size());
  std::vector<double> prefix(static_cast<std::size_t>(L) + 1, 0.0);
  for (Id k = 0; k < L; ++k) prefix[k + 1] = prefix[k] + static_cast<double>(triangles[k]) + static_cast<double>(nxy) / 100.0;
  std::vector<Id> bounds(static_cast<std::size_t>(P) + 1, 0);
  bounds[P] = L;
  for (int q = 1; q < P; ++q) {
    const double target = prefix[L] * q / P;
    Id b = static_cast<Id>(std::lower_bound(prefix.begin(), prefix.end(), target) - prefix.begin());
    b = std::max(b, bounds[q - 1] + 1);
    b = std::min(b, L - (P - q));
    bounds[q] = b;
  }
  return bounds;
}

}  // namespace

namespace {

// Planes of the volume held by this rank: [lo, hi] (inclusive) in `grid`.
struct HeldSlab {
  ImageGrid grid;
  Id lo = 0, hi = -1;
};

// A slab of `count` planes shaped like the volume.
ImageGrid new_slab(const ImageGrid& head, Id count) {
  ImageGrid g;
  g.spacing = head.spacing;
  g.origin = head.origin;
  g.name = head.name;
  g.allocate({head.dims[0], head.dims[1], count}, head.type);
  return g;
}

// With balance: read the equal slab, count its layers' triangles, share the
// counts, and move the boundaries so that every rank gets the same work.
// Returns the slab read (its planes are kept for the final read).
HeldSlab balance(PlaneSource& source, const generate::ContourOptions& options, std::vector<Id>& bounds,
                 int r, RankStats& st) {
  const ImageGrid& head = source.header();
  const int P = static_cast<int>(bounds.size()) - 1;
  auto t0 = Clock::now();
  HeldSlab held;
  held.lo = bounds[r];
  held.hi = bounds[r + 1];
  std::vector<Id> mine;
  // This rank's reading and counting, then the ranks agree: a slab one
  // rank cannot read ends every rank here (SharedError), none left waiting.
  agreed([&] {
    held.grid = new_slab(head, held.hi - held.lo + 1);
    source.read_planes(held.lo, held.hi - held.lo + 1, held.grid.bytes.data());
    st.read = seconds_since(t0);
    t0 = Clock::now();
    mine = generate::triangles_per_layer(held.grid, options);
  });
  std::vector<long long> counts(mine.begin(), mine.end()), all(static_cast<std::size_t>(head.dims[2] - 1));
  std::vector<int> sizes(static_cast<std::size_t>(P)), displs(static_cast<std::size_t>(P));
  for (int q = 0; q < P; ++q) {
    sizes[q] = checked_int(bounds[q + 1] - bounds[q], "voxel layers");
    displs[q] = checked_int(bounds[q], "voxel layers");
  }
  mpi().Allgatherv(counts.data(), sizes[r], mpi().long_long, all.data(), sizes.data(), displs.data(), mpi().long_long,
                   mpi().comm_world);
  bounds = balanced_bounds(all, head.dims[0] * head.dims[1], P);
  st.balance = seconds_since(t0);
  return held;
}

// Planes [first, last] of the final slab: those already held are copied
// (or kept as they are when the boundaries did not move), the others read.
ImageGrid read_slab(PlaneSource& source, HeldSlab held, Id first, Id last) {
  if (first == held.lo && last == held.hi) return std::move(held.grid);
  const ImageGrid& head = source.header();
  ImageGrid slab = new_slab(head, last - first + 1);
  const std::size_t plane = static_cast<std::size_t>(head.dims[0] * head.dims[1]) * scalar_size(head.type);
  const Id keep_lo = std::max(first, held.lo), keep_hi = std::min(last, held.hi);
  if (keep_lo > keep_hi) {
    source.read_planes(first, last - first + 1, slab.bytes.data());
    return slab;
  }
  std::copy_n(held.grid.bytes.data() + plane * static_cast<std::size_t>(keep_lo - held.lo),
              plane * static_cast<std::size_t>(keep_hi - keep_lo + 1),
              slab.bytes.data() + plane * static_cast<std::size_t>(keep_lo - first));
  if (first < keep_lo) source.read_planes(first, keep_lo - first, slab.bytes.data());
  if (keep_hi < last)
    source.read_planes(keep_hi + 1, last - keep_hi, slab.bytes.data() + plane * static_cast<std::size_t>(keep_hi + 1 - first));
  return slab;
}

// This rank's slab, planes [first, last] of which `below` and `above` are
// ghost planes, read and contoured into `piece` (its mesh and keys, and how
// the gather treats them); with averaged normals, `normal_sums` gets
// KEY-REDUCE's merge over this rank's triangles.
void contour_slab(PlaneSource& source, HeldSlab held, const generate::ContourOptions& options, ContourPiece& piece,
                  Id first, Id last, Id below, Id above, std::size_t memory_limit, std::vector<Vec3f>& normal_sums) {
  const ImageGrid& head = source.header();
  const Id nz = head.dims[2], nxy = head.dims[0] * head.dims[1];
  RankStats& st = piece.stats;
  auto t0 = Clock::now();
  generate::ContourOptions opt = options;
  opt.first_plane = first;
  opt.total_planes = nz;
  opt.ghost_below = below;
  opt.ghost_above = above;
  piece.average = options.normals == generate::ContourNormals::Average;
  piece.layer_grid = generate::LayerGrid{static_cast<std::uint64_t>(nxy), nz - 1, static_cast<Id>(options.isovalues.size())};
  if (options.normals == generate::ContourNormals::Average) opt.normals = generate::ContourNormals::None;
  if (memory_limit) {
    // --memory-limit: the rank's planes in slabs, merged by key: the same
    // mesh and keys as one contour of them.
    generate::StreamStats ss;
    piece.mesh = generate::contour_planes_streamed(source, opt, memory_limit, first + below, last - above, piece.keys,
                                                   nullptr, &ss);
    st.read += ss.read;
    st.slabs = static_cast<double>(ss.slabs);
  } else {
    st.slabs = 1;
    ImageGrid slab = read_slab(source, std::move(held), first, last);
    st.read += seconds_since(t0);
    t0 = Clock::now();
    piece.mesh = generate::contour(slab, opt, nullptr, &piece.keys);
    free_storage(slab.bytes);
  }
  if (piece.average) normal_sums = point_normal_sums(piece.mesh);
  st.contour = seconds_since(t0);
}

// The distributed KEY-REDUCE of the piece's keys. Keys are isovalue-major
// (isovalue * 3 * points + 3 * point + axis); rank q owns the points of
// planes [lo_q, lo_{q+1}), the last rank also the top plane. Averaged
// normals: the shared planes' partial sums merge at their owners (the rest
// of the merge); then the transform, normalising, on every copy alike.
void number_piece(ContourPiece& piece, const generate::ContourOptions& options, const std::vector<Id>& bounds,
                  Id nxy, Id nz, std::vector<Vec3f>* normal_sums) {
  const int P = static_cast<int>(bounds.size()) - 1;
  const int segments = static_cast<int>(options.isovalues.size());
  const std::uint64_t per_iso = 3ull * static_cast<std::uint64_t>(nxy * nz);
  const auto first_key = [&](int iso, int q) -> std::uint64_t {
    const std::uint64_t base = static_cast<std::uint64_t>(iso) * per_iso;
    if (q == P) return base + per_iso;
    return base + std::uint64_t{3} * static_cast<std::uint64_t>(nxy) * static_cast<std::uint64_t>(bounds[q]);
  };
  std::vector<Vec3f> none;
  const ValueMerge merge = value_merge(normal_sums ? *normal_sums : none, add);
  piece.numbering = number_keys(piece.keys, segments, first_key, normal_sums ? &merge : nullptr);
  if (normal_sums) {
    normalize(normal_sums->data(), piece.mesh.num_points());
    piece.mesh.point_fields.push_back(normals_field(*normal_sums));
  }
  const GlobalNumbering& g = piece.numbering;
  if (g.total > static_cast<long long>(std::numeric_limits<PointIndex>::max()))
    throw LimitError("distributed contour: " + std::to_string(g.total) + " points exceed 32-bit point ids");
  RankStats& st = piece.stats;
  st.points = static_cast<double>(piece.mesh.num_points());
  st.fine_points_held = st.points;
  for (std::uint8_t o : g.owned) st.points_owned += o;
  st.triangles = static_cast<double>(piece.mesh.num_cells());
  st.keys_requested = static_cast<double>(g.keys_requested);
  st.bytes_sent = static_cast<double>(g.bytes_sent);
}

}  // namespace

ContourPiece contour_piece(PlaneSource& source, const generate::ContourOptions& options, bool balance_work,
                           std::size_t memory_limit) {
  int P = 1, r = 0;
  mpi().Comm_size(mpi().comm_world, &P);
  mpi().Comm_rank(mpi().comm_world, &r);
  const ImageGrid& head = source.header();
  require_distributable(head, options, P);
  if (options.coarsen) throw InputError("distributed contour: --coarsen is coarse_piece's (internal error)");
  const Id nz = head.dims[2], nxy = head.dims[0] * head.dims[1];
  ContourPiece piece;
  RankStats& st = piece.stats;
  // Rank q's voxel layers [bounds[q], bounds[q + 1]) need planes bounds[q] .. bounds[q + 1].
  std::vector<Id> bounds(static_cast<std::size_t>(P) + 1);
  for (int q = 0; q <= P; ++q) bounds[q] = (nz - 1) * q / P;
  HeldSlab held;
  if (balance_work && P > 1) held = balance(source, options, bounds, r, st);
  const Id lo = bounds[r], hi = bounds[r + 1];
  st.first_plane = static_cast<double>(lo);
  st.planes = static_cast<double>(hi - lo + 1);
  // Gradient normals and curvature take central differences across the
  // slab's border: a ghost plane on either side (where the grid has one).
  const bool ghosts = options.normals == generate::ContourNormals::Gradient || options.curvature;
  const Id below = ghosts && lo > 0 ? 1 : 0, above = ghosts && hi < nz - 1 ? 1 : 0;
  // This rank's reading and contouring, then the ranks agree (the
  // exchange's start: its wait for the slowest rank is the load imbalance,
  // timed apart): an error on any rank ends every rank here.
  std::vector<Vec3f> normal_sums;
  const std::string error = error_of([&] {
    contour_slab(source, std::move(held), options, piece, lo - below, hi + above, below, above, memory_limit,
                 normal_sums);
  });
  auto t0 = Clock::now();
  share(error);
  st.wait = seconds_since(t0);
  t0 = Clock::now();
  number_piece(piece, options, bounds, nxy, nz, piece.average ? &normal_sums : nullptr);
  st.exchange = seconds_since(t0);
  return piece;
}

std::vector<Id> slab_bounds(PlaneSource& source, const generate::ContourOptions& options, bool balance_work) {
  int P = 1, r = 0;
  mpi().Comm_size(mpi().comm_world, &P);
  mpi().Comm_rank(mpi().comm_world, &r);
  const Id nz = source.header().dims[2];
  std::vector<Id> bounds(static_cast<std::size_t>(P) + 1);
  for (int q = 0; q <= P; ++q) bounds[q] = (nz - 1) * q / P;
  RankStats unused;
  if (balance_work && P > 1) balance(source, options, bounds, r, unused);
  return bounds;
}

FineLayers contour_layers(PlaneSource& source, const generate::ContourOptions& options, Id first, Id end,
                          std::size_t memory_limit) {
  const ImageGrid& head = source.header();
  const Id nz = head.dims[2];
  // Derivatives read a ghost plane beyond the layers, where the grid has one.
  const bool ghosts = options.normals == generate::ContourNormals::Gradient || options.curvature;
  const Id below = ghosts && first > 0 ? 1 : 0, above = ghosts && end < nz - 1 ? 1 : 0;
  generate::ContourOptions opt = options;
  opt.total_planes = nz;
  opt.coarsen = false;  // the caller coarsens the layers with their nearest grid points
  if (options.normals == generate::ContourNormals::Average) opt.normals = generate::ContourNormals::None;
  FineLayers out;
  auto t0 = Clock::now();
  if (memory_limit) {
    // The planes in slabs (their ghost planes read alike), merged by key.
    generate::StreamStats ss;
    out.mesh = generate::contour_planes_streamed(source, opt, memory_limit, first, end, out.keys, &out.nearest, &ss);
    out.read = ss.read;
    out.contour = seconds_since(t0) - ss.read;
    out.slabs = ss.slabs;
    return out;
  }
  ImageGrid slab = read_slab(source, HeldSlab{}, first - below, end + above);
  out.read = seconds_since(t0);
  t0 = Clock::now();
  opt.first_plane = first - below;
  opt.ghost_below = below;
  opt.ghost_above = above;
  out.mesh = generate::contour(slab, opt, nullptr, &out.keys, &out.nearest);
  out.contour = seconds_since(t0);
  return out;
}

SurfaceMesh gather(ContourPiece& piece, std::vector<std::uint64_t>* point_keys) {
  const auto t0 = Clock::now();
  int P = 1, r = 0;
  mpi().Comm_size(mpi().comm_world, &P);
  mpi().Comm_rank(mpi().comm_world, &r);
  const SurfaceMesh& m = piece.mesh;
  const GlobalNumbering& g = piece.numbering;
  const int S = g.segments;
  // Owned points (positions and fields) in local order: key order, segment after segment.
  const Id n = m.num_points();
  std::vector<float> xyz;
  std::vector<std::uint64_t> keys;
  std::vector<std::vector<float>> fields(m.point_fields.size());
  xyz.reserve(static_cast<std::size_t>(3 * piece.stats.points_owned));
  for (Id p = 0; p < n; ++p)
    if (g.owned[p]) {
      xyz.insert(xyz.end(), m.points.begin() + 3 * p, m.points.begin() + 3 * p + 3);
      if (piece.average || point_keys) keys.push_back(piece.keys[static_cast<std::size_t>(p)]);
      for (std::size_t f = 0; f < fields.size(); ++f) {
        const Field& fd = m.point_fields[f];
        fields[f].insert(fields[f].end(), fd.values.begin() + fd.components * p, fd.values.begin() + fd.components * (p + 1));
      }
    }
  // Triangles in global ids; a triangle's segment is its points' (an isovalue's).
  std::vector<long long> my_tris(static_cast<std::size_t>(S), 0);
  std::vector<PointIndex> conn(m.connectivity.size());
  auto segment_of_id = [&](std::uint64_t id) {
    int s = 0;
    while (s + 1 < S && static_cast<long long>(id) >= g.first_id(s + 1, 0)) ++s;
    return s;
  };
  for (Id t = 0; t < m.num_cells(); ++t) {
    for (int c = 0; c < 3; ++c) conn[3 * t + c] = static_cast<PointIndex>(g.ids[m.connectivity[3 * t + c]]);
    ++my_tris[static_cast<std::size_t>(segment_of_id(conn[3 * t]))];
  }
  std::vector<long long> tri_counts(static_cast<std::size_t>(P) * S);
  mpi().Allgather(my_tris.data(), S, mpi().long_long, tri_counts.data(), S, mpi().long_long, mpi().comm_world);

  SurfaceMesh out;
  gather_segments(xyz, 3, mpi().float_, g.counts, S, out.points);
  for (std::size_t f = 0; f < fields.size(); ++f) {
    Field whole{m.point_fields[f].name, m.point_fields[f].components, {}};
    gather_segments(fields[f], whole.components, mpi().float_, g.counts, S, whole.values);
    if (r == 0) out.point_fields.push_back(std::move(whole));
  }
  static_assert(sizeof(PointIndex) == 4, "the gather sends point ids as MPI_UINT32_T");
  gather_segments(conn, 3, mpi().uint32, tri_counts, S, out.connectivity);
  if (piece.average || point_keys) {
    std::vector<std::uint64_t> all_keys;
    gather_segments(keys, 1, mpi().uint64, g.counts, S, all_keys);
    if (r == 0 && piece.average)
      for (Field& f : out.point_fields)
        if (f.name == "Normals")
          f = generate::blocked_average_normals(out, generate::layer_blocks(out, all_keys, piece.layer_grid));
    if (point_keys) *point_keys = std::move(all_keys);
  }
  piece.stats.output += seconds_since(t0);
  return out;
}

namespace {

// The bytes of one triangle sent as a ghost: per corner its global id, its
// edge key, its position and its point field values, then the cell field values.
struct GhostRecord {
  std::size_t corner_bytes = 0, bytes = 0;
  explicit GhostRecord(const SurfaceMesh& m) {
    std::size_t point_values = 3, cell_values = 0;
    for (const Field& f : m.point_fields) point_values += static_cast<std::size_t>(f.components);
    for (const Field& f : m.cell_fields) cell_values += static_cast<std::size_t>(f.components);
    corner_bytes = 16 + 4 * point_values;
    bytes = 3 * corner_bytes + 4 * cell_values;
  }
};

void append_ghost_record(const SurfaceMesh& m, const std::vector<std::uint64_t>& ids,
                         const std::vector<std::uint64_t>& keys, Id t, const GhostRecord& record,
                         std::vector<char>& buf) {
  std::size_t at = buf.size();
  buf.resize(at + record.bytes);
  for (int c = 0; c < 3; ++c) {
    const PointIndex p = m.connectivity[3 * t + c];
    std::memcpy(buf.data() + at, &ids[p], 8);
    std::memcpy(buf.data() + at + 8, &keys[p], 8);
    std::memcpy(buf.data() + at + 16, m.points.data() + 3 * static_cast<std::size_t>(p), 12);
    at += 28;
    for (const Field& f : m.point_fields) {
      const auto k = static_cast<std::size_t>(f.components);
      std::memcpy(buf.data() + at, f.values.data() + k * p, 4 * k);
      at += 4 * k;
    }
  }
  for (const Field& f : m.cell_fields) {
    const auto k = static_cast<std::size_t>(f.components);
    std::memcpy(buf.data() + at, f.values.data() + k * static_cast<std::size_t>(t), 4 * k);
    at += 4 * k;
  }
}

// The triangles rank r sends to its neighbours r - 1 and r + 1: those with a
// point on the plane that neighbour shares (lo below, hi above).
std::vector<std::vector<char>> ghost_records_to_send(const ContourPiece& piece, const SurfaceMesh& m,
                                                     const std::vector<std::uint64_t>& ids, int P, int r,
                                                     const GhostRecord& record) {
  // A point's plane and axis from its key (isovalue * per_iso + 3 * grid point + axis):
  // rank r - 1 holds the in-plane crossings of plane lo, rank r + 1 those of plane hi.
  const std::uint64_t nxy = piece.layer_grid.nxy;
  const std::uint64_t per_iso = 3 * nxy * static_cast<std::uint64_t>(piece.layer_grid.layers + 1);
  const auto lo = static_cast<std::uint64_t>(piece.stats.first_plane);
  const auto hi = lo + static_cast<std::uint64_t>(piece.stats.planes) - 1;
  const auto shared_plane = [&](PointIndex p) -> std::uint64_t {  // lo, hi, or neither (~0)
    const std::uint64_t k = piece.keys[p] % per_iso;
    if (k % 3 == 2) return ~std::uint64_t{0};
    const std::uint64_t z = k / 3 / nxy;
    return z == lo || z == hi ? z : ~std::uint64_t{0};
  };
  std::vector<std::vector<char>> to(static_cast<std::size_t>(P));
  for (Id t = 0; t < m.num_cells(); ++t) {
    bool below = false, above = false;
    for (int c = 0; c < 3; ++c) {
      const std::uint64_t z = shared_plane(m.connectivity[3 * t + c]);
      below = below || (z == lo && r > 0);
      above = above || (z == hi && r + 1 < P);
    }
    if (below) append_ghost_record(m, ids, piece.keys, t, record, to[static_cast<std::size_t>(r - 1)]);
    if (above) append_ghost_record(m, ids, piece.keys, t, record, to[static_cast<std::size_t>(r + 1)]);
  }
  return to;
}

// Every rank's buffers to every other, in rank order: one Alltoallv.
std::vector<char> exchange_bytes(const std::vector<std::vector<char>>& to, int P) {
  std::vector<int> send_counts(static_cast<std::size_t>(P)), recv_counts(static_cast<std::size_t>(P));
  std::vector<int> send_displs(static_cast<std::size_t>(P)), recv_displs(static_cast<std::size_t>(P));
  std::vector<char> sent;
  for (int q = 0; q < P; ++q) {
    send_displs[q] = checked_int(static_cast<long long>(sent.size()), "ghost cells");
    send_counts[q] = checked_int(static_cast<long long>(to[q].size()), "ghost cells");
    sent.insert(sent.end(), to[q].begin(), to[q].end());
  }
  mpi().Alltoall(send_counts.data(), 1, mpi().int_, recv_counts.data(), 1, mpi().int_, mpi().comm_world);
  long long received = 0;
  for (int q = 0; q < P; ++q) {
    recv_displs[q] = checked_int(received, "ghost cells");
    received += recv_counts[q];
  }
  std::vector<char> got(static_cast<std::size_t>(checked_int(received, "ghost cells")));
  mpi().Alltoallv(sent.data(), send_counts.data(), send_displs.data(), mpi().byte, got.data(), recv_counts.data(),
                  recv_displs.data(), mpi().byte, mpi().comm_world);
  return got;
}

// Reads `count` float values at v into `values`; returns v past them.
const char* append_floats(const char* v, int count, Array<float>& values) {
  for (int k = 0; k < count; ++k, v += 4) {
    float value;
    std::memcpy(&value, v, 4);
    values.push_back(value);
  }
  return v;
}

// Keeps the received triangles that use a point this rank holds (one of its
// first n); their other points join the piece once each, in the order received.
void append_ghosts(GhostedPiece& out, Id n, const std::vector<char>& got, const GhostRecord& record) {
  std::unordered_map<std::uint64_t, PointIndex> local;
  for (Id p = 0; p < n; ++p) local.emplace(out.ids[p], static_cast<PointIndex>(p));
  SurfaceMesh& o = out.mesh;
  for (std::size_t at = 0; at + record.bytes <= got.size(); at += record.bytes) {
    std::uint64_t id[3];
    bool touches = false;
    for (int c = 0; c < 3; ++c) {
      std::memcpy(&id[c], got.data() + at + c * record.corner_bytes, 8);
      const auto it = local.find(id[c]);
      touches = touches || (it != local.end() && static_cast<Id>(it->second) < n);
    }
    if (!touches) continue;
    for (int c = 0; c < 3; ++c) {
      auto [it, added] = local.emplace(id[c], static_cast<PointIndex>(o.num_points()));
      if (added) {
        const char* v = got.data() + at + c * record.corner_bytes + 8;
        std::uint64_t key;
        std::memcpy(&key, v, 8);
        out.keys.push_back(key);
        v = append_floats(v + 8, 3, o.points);
        for (Field& f : o.point_fields) v = append_floats(v, f.components, f.values);
        out.ids.push_back(id[c]);
        out.point_ghosts.push_back(1);
      }
      o.connectivity.push_back(it->second);
    }
    const char* v = got.data() + at + 3 * record.corner_bytes;
    for (Field& f : o.cell_fields) v = append_floats(v, f.components, f.values);
    out.cell_ghosts.push_back(1);
  }
}

}  // namespace

GhostedPiece ghosted_piece(ContourPiece& piece) {
  int P = 1, r = 0;
  mpi().Comm_size(mpi().comm_world, &P);
  mpi().Comm_rank(mpi().comm_world, &r);
  GhostedPiece out;
  out.mesh = std::move(piece.mesh);
  out.ids = std::move(piece.numbering.ids);
  const Id n = out.mesh.num_points(), cells = out.mesh.num_cells();
  out.point_ghosts.resize(static_cast<std::size_t>(n));
  out.cell_ghosts.assign(static_cast<std::size_t>(cells), 0);
  for (Id p = 0; p < n; ++p) out.point_ghosts[p] = piece.numbering.owned[p] ? 0 : 1;
  if (P == 1) {
    out.keys = std::move(piece.keys);
    return out;
  }
  if (!out.mesh.all_triangles()) throw InputError("distributed contour: ghost cells of a piece with polygons");
  const GhostRecord record(out.mesh);
  const std::vector<char> got = exchange_bytes(ghost_records_to_send(piece, out.mesh, out.ids, P, r, record), P);
  out.keys = std::move(piece.keys);
  append_ghosts(out, n, got, record);
  return out;
}

std::vector<RankStats> gather_stats(const RankStats& mine) {
  int P = 1, r = 0;
  mpi().Comm_size(mpi().comm_world, &P);
  mpi().Comm_rank(mpi().comm_world, &r);
  static_assert(std::is_trivially_copyable_v<RankStats> && sizeof(RankStats) % sizeof(double) == 0);
  constexpr int n = sizeof(RankStats) / sizeof(double);
  std::vector<RankStats> all(r == 0 ? static_cast<std::size_t>(P) : 0);
  mpi().Gather(&mine, n, mpi().double_, all.data(), n, mpi().double_, 0, mpi().comm_world);
  return all;
}

}  // namespace keymesh::distributed

#endif
