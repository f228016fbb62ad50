#include "keymesh/core/work_estimate.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "keymesh/core/error.hpp"

namespace keymesh {

namespace {

// Bytes per point: three float coordinates and the carried fields, twice (the
// generator's values and the welded copy).
std::uint64_t point_bytes(std::uint64_t field_components) {
  return saturating_mul(2, saturating_add(12, saturating_mul(4, field_components)));
}

}  // namespace

// Bytes below 1 KiB, otherwise KiB, MiB ... with four significant digits;
// long double so that a size past 2^64 (a zero-stride view's claim) prints.
std::string size_text(long double bytes) {
  if (bytes < 1024) {
    const auto n = static_cast<unsigned long long>(bytes);
    return std::to_string(n) + (n == 1 ? " byte" : " bytes");
  }
  static const char* const units[] = {"KiB", "MiB", "GiB", "TiB", "PiB", "EiB", "ZiB", "YiB"};
  long double v = bytes / 1024;
  int u = 0;
  while (v >= 1024 && u < 7) v /= 1024, ++u;
  char b[64];
  std::snprintf(b, sizeof b, "%.4Lg %s", v, units[u]);
  return b;
}

std::uint64_t saturating_mul(std::uint64_t a, std::uint64_t b) {
  if (a != 0 && b > UINT64_MAX / a) return UINT64_MAX;
  return a * b;
}

std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b) { return b > UINT64_MAX - a ? UINT64_MAX : a + b; }

std::uint64_t default_memory_budget() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  std::uint64_t budget = pages > 0 && page > 0 ? saturating_mul(std::uint64_t(pages), std::uint64_t(page)) : UINT64_MAX;
  rlimit as{};
  if (::getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY)
    budget = std::min<std::uint64_t>(budget, as.rlim_cur);
  return budget;
}

void check_work(const WorkEstimate& work, std::uint64_t budget, const std::string& what, std::uint64_t max_points,
                std::uint64_t max_cells) {
  const std::string sizes = std::to_string(work.points) + " points, " + std::to_string(work.cells) + " cells";
  if (work.points > max_points)
    throw LimitError(what + ": " + sizes + ": more than the " + std::to_string(max_points) +
                     " points the index type holds");
  if (work.cells > max_cells)
    throw LimitError(what + ": " + sizes + ": more than the " + std::to_string(max_cells) +
                     " cells the index type holds");
  check_memory(work.bytes, budget, what + ": " + sizes);
}

void check_memory(std::uint64_t bytes, std::uint64_t budget, const std::string& what) {
  if (bytes <= budget) return;
  std::string need = size_text(bytes), have = size_text(budget);
  if (need == have)  // close enough to print alike: the exact counts
    need = std::to_string(bytes) + " bytes", have = std::to_string(budget) + " bytes";
  throw LimitError(what + " need about " + need + ", more than the " + have +
                   " of --max-memory (default: this machine's memory or ulimit -v)");
}

namespace {
// Uniform subdivision: every level adds at most one point per edge of every
// cell (fewer when cells share edges) and splits each cell into `children`.
// Bytes: the points, `cell_bytes` per output cell, and KEY-REDUCE's (key,
// value) pairs of 16 bytes for each edge of the last level's parents.
WorkEstimate estimate_subdivide(std::uint64_t points, std::uint64_t cells, int levels, std::uint64_t edges_per_cell,
                                std::uint64_t children, std::uint64_t cell_bytes, std::uint64_t field_components) {
  WorkEstimate w{points, cells, 0};
  std::uint64_t parents = cells;
  for (int l = 0; l < levels; ++l) {
    parents = w.cells;
    w.points = saturating_add(w.points, saturating_mul(edges_per_cell, w.cells));
    w.cells = saturating_mul(children, w.cells);
  }
  w.bytes = saturating_add(saturating_mul(w.points, point_bytes(field_components)),
                           saturating_add(saturating_mul(w.cells, cell_bytes),
                                          saturating_mul(saturating_mul(parents, edges_per_cell), 16)));
  return w;
}
}  // namespace

WorkEstimate estimate_subdivide_triangles(std::uint64_t points, std::uint64_t triangles, int levels,
                                          std::uint64_t field_components) {
  return estimate_subdivide(points, triangles, levels, 3, 4, 12, field_components);  // 3 ids of 4 bytes
}

WorkEstimate estimate_subdivide_tets(std::uint64_t points, std::uint64_t tets, int levels,
                                     std::uint64_t field_components) {
  // 4 ids of 8 bytes, a type byte and an 8-byte offset per tet.
  return estimate_subdivide(points, tets, levels, 6, 8, 41, field_components);
}

WorkEstimate estimate_dual(std::uint64_t points, std::uint64_t cells, std::uint64_t corners,
                           std::uint64_t field_components) {
  // A point per cell (its fields averaged), a polygon per point whose
  // corners are that point's cells: as many corners as the input's, with
  // an 8-byte offset per polygon.
  WorkEstimate w{cells, points, 0};
  w.bytes = saturating_add(saturating_mul(cells, point_bytes(field_components)),
                           saturating_add(saturating_mul(corners, 4), saturating_mul(points, 8)));
  return w;
}

WorkEstimate estimate_tetrahedralize(std::uint64_t points, std::uint64_t hexes, int tets_per_hex,
                                     std::uint64_t field_components) {
  WorkEstimate w{points, saturating_mul(hexes, std::uint64_t(tets_per_hex)), 0};
  if (tets_per_hex == 24)  // a centre per cell and (at most) one per face
    w.points = saturating_add(w.points, saturating_mul(hexes, 7));
  w.bytes = saturating_add(saturating_mul(w.points, point_bytes(field_components)), saturating_mul(w.cells, 41));
  return w;
}

}  // namespace keymesh
