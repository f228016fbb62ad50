#include "contour_limits.hpp"

#include <limits>
#include <string>

#include "keymesh/core/error.hpp"

namespace keymesh::cuda {

namespace {

constexpr Id kMaxItems = std::numeric_limits<int>::max();  // CUB's num_items

[[noreturn]] void not_on_gpu(const std::string& what) {
  throw InputError("--backend cuda: " + what + " is not available on the GPU yet (use --backend cpu)");
}

}  // namespace

void check_gpu_options(const generate::ContourOptions& opt) {
  if (opt.weld == generate::ContourWeld::VertexWeld) not_on_gpu("VERTEX-WELD (--weld vertexweld)");
  if (opt.coarsen) not_on_gpu("coarsening (--coarsen)");
  if (opt.curvature) not_on_gpu("curvature (--curvature)");
  if (opt.history) not_on_gpu("per-point history (--history)");
  if (opt.output_arrays) not_on_gpu("writing into arrays the caller owns (output_arrays)");
  if (opt.total_planes) not_on_gpu("streamed (slab) contouring");
  if (opt.ghost_below || opt.ghost_above) not_on_gpu("a grid with ghost planes");
}

Id gpu_voxels(Id nx, Id ny, Id nz) {
  const Id voxels = (nx - 1) * (ny - 1) * (nz - 1);
  if (voxels > kMaxItems)
    throw LimitError("--backend cuda: " + std::to_string(voxels) + " voxels exceed 2^31 - 1 (use --backend cpu)");
  return voxels;
}

Id gpu_soup_corners(Id corners, std::uint64_t triangles) {
  // Compared before multiplying: 3 * triangles cannot wrap a 64-bit Id here.
  const std::uint64_t room = static_cast<std::uint64_t>(kMaxItems - corners) / 3;
  if (triangles > room)
    throw LimitError("--backend cuda: " + std::to_string(static_cast<std::uint64_t>(corners / 3) + triangles) +
                     " triangles exceed the device sort's 2^31 - 1 corners (use --backend cpu)");
  return corners + 3 * static_cast<Id>(triangles);
}

}  // namespace keymesh::cuda
