#pragma once
// Work estimated before it starts: a command computes the size of what it is
// about to produce (points, cells, bytes) from its input's counts and refuses
// by name what exceeds the index type or the memory it may use, instead of
// allocating for seconds and ending in the OOM killer or a bad_alloc that
// names nothing.
#include <cstdint>
#include <string>

namespace keymesh {

// What an operation will produce. Counts saturate at UINT64_MAX rather than
// wrap, so an absurd request stays absurd.
struct WorkEstimate {
  std::uint64_t points = 0;
  std::uint64_t cells = 0;
  std::uint64_t bytes = 0;  // peak bytes of the output and the work arrays building it
};

// a * b and a + b, saturating at UINT64_MAX.
std::uint64_t saturating_mul(std::uint64_t a, std::uint64_t b);
std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b);

// Memory a command may use unless told otherwise: the machine's physical
// memory, or the address-space limit (ulimit -v) when that is lower.
std::uint64_t default_memory_budget();

// Throws LimitError "<what>: N points, M cells need about B MiB ..." when the
// estimate passes `max_points` / `max_cells` (the index type) or `budget` bytes.
void check_work(const WorkEstimate& work, std::uint64_t budget, const std::string& what,
                std::uint64_t max_points = UINT64_MAX, std::uint64_t max_cells = UINT64_MAX);

// A size with the unit that shows it: "512 bytes", "22.69 KiB", "1.278 GiB"
// (four significant digits), for every message that names a size.
std::string size_text(long double bytes);

// Throws LimitError "<what> need about B, more than the L of --max-memory
// ..." when `bytes` pass `budget`; sizes in bytes, KiB, MiB ... as they
// show the two apart.
void check_memory(std::uint64_t bytes, std::uint64_t budget, const std::string& what);

// Estimates of the generators whose output size follows from their input's
// counts alone (field_components: float values per point carried along).
WorkEstimate estimate_subdivide_triangles(std::uint64_t points, std::uint64_t triangles, int levels,
                                          std::uint64_t field_components);
WorkEstimate estimate_subdivide_tets(std::uint64_t points, std::uint64_t tets, int levels,
                                     std::uint64_t field_components);
// The dual of a surface of `points`, `cells` and `corners` (connectivity entries).
WorkEstimate estimate_dual(std::uint64_t points, std::uint64_t cells, std::uint64_t corners,
                           std::uint64_t field_components);
// tets_per_hex 5 or 24; hexes and points of the input (a voxel grid of N^3
// points has (N-1)^3 hexes); scheme 24 adds a point per face and per cell.
WorkEstimate estimate_tetrahedralize(std::uint64_t points, std::uint64_t hexes, int tets_per_hex,
                                     std::uint64_t field_components);

}  // namespace keymesh
