// The distributed entry points when keymesh is built without MPI: a world of
// one rank; the CLI refuses a multi-rank launch by name (see main.cpp).
#include "keymesh/distributed/contour_distributed.hpp"
#include "keymesh/distributed/mpi.hpp"

#if !defined(KEYMESH_HAVE_MPI)

#include <cstdlib>

#include "keymesh/core/error.hpp"

namespace keymesh::distributed {

namespace {
[[noreturn]] void not_built() {
  throw InputError("distributed contour: keymesh was built without MPI (install libopenmpi-dev and rebuild)");
}
}  // namespace

bool compiled() { return false; }
void init(int*, char***) {}
void finalize() {}
int rank() { return 0; }
int size() { return 1; }
void abort_all(int code) { std::exit(code); }
bool all_ok(bool ok) { return ok; }
std::string first_error(const std::string& mine) { return mine; }
std::vector<std::vector<std::byte>> all_gather_bytes(const std::vector<std::byte>& mine) { return {mine}; }
std::vector<std::vector<std::byte>> gather_bytes(const std::vector<std::byte>& mine) { return {mine}; }
void gather_chunks(const std::function<bool(std::vector<std::byte>&)>& next,
                   const std::function<void(int, const std::vector<std::byte>&)>& take) {
  std::vector<std::byte> chunk;
  while (next(chunk)) take(0, chunk);
}

GlobalNumbering number_keys(std::span<const std::uint64_t>, int, const std::function<std::uint64_t(int, int)>&,
                            const ValueMerge*) {
  not_built();
}
void require_distributable(const ImageGrid&, const generate::ContourOptions&, int) { not_built(); }
ContourPiece contour_piece(PlaneSource&, const generate::ContourOptions&, bool, std::size_t) { not_built(); }
SurfaceMesh gather(ContourPiece&, std::vector<std::uint64_t>*) { not_built(); }
GhostedPiece ghosted_piece(ContourPiece&) { not_built(); }
std::vector<Id> slab_bounds(PlaneSource&, const generate::ContourOptions&, bool) { not_built(); }
FineLayers contour_layers(PlaneSource&, const generate::ContourOptions&, Id, Id, std::size_t) { not_built(); }
std::vector<RankStats> gather_stats(const RankStats&) { not_built(); }

}  // namespace keymesh::distributed

#endif
