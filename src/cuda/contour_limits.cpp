#include "contour_limits.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "keymesh/core/error.hpp"
#include "keymesh/cuda/device_contour.hpp"
#include "keymesh/mesh/label_scalars.hpp"

namespace keymesh::cuda {

namespace {

constexpr Id kMaxItems = std::numeric_limits<int>::max();  // CUB's num_items

[[noreturn]] void not_on_gpu(const std::string& what) {
  throw InputError("--backend cuda: " + what + " is not available on the GPU yet (use --backend cpu)");
}

}  // namespace

void check_gpu_options(const generate::ContourOptions& opt) {
  if (opt.history) not_on_gpu("per-point history (--history)");
  if (opt.output_arrays) not_on_gpu("writing into arrays the caller owns (output_arrays)");
  if (opt.total_planes) not_on_gpu("streamed (slab) contouring");
  if (opt.ghost_below || opt.ghost_above) not_on_gpu("a grid with ghost planes");
}

void check_device_volume(const DeviceVolume& volume, const generate::ContourOptions& opt) {
  check_gpu_options(opt);
  // cuda::contour coarsens host samples; the device-resident entry hands out
  // device arrays, and the coarsening's split runs on the host.
  if (opt.coarsen) not_on_gpu("coarsening (--coarsen) of samples in device memory");
  // generate::check_contour_input's checks but the byte count: the samples
  // are not the grid's own (its bytes stay empty), they are device memory.
  if (opt.isovalues.empty()) throw InputError("contour: no isovalue given");
  for (double iso : opt.isovalues)
    if (!std::isfinite(iso)) throw InputError("contour: isovalue " + std::to_string(iso) + " is not finite");
  const ImageGrid& g = volume.grid;
  for (int a = 0; a < 3; ++a)
    if (g.dims[a] < 2)
      throw InputError("contour: grid has " + std::to_string(g.dims[a]) + " point(s) along axis " + "xyz"[a] +
                       std::string(" (need at least 2)"));
  if (!is_grid_scalar(g.type))
    throw InputError("contour: " + wide_samples_refusal(g.type));
  if (!volume.samples) throw InputError("--backend cuda: the volume's device pointer is null");
  gpu_voxels(g.dims[0], g.dims[1], g.dims[2]);
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
