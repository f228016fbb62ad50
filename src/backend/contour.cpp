#include "keymesh/backend/contour.hpp"

#include "keymesh/core/error.hpp"
#include "keymesh/cuda/backend.hpp"
#include "keymesh/cuda/unstructured.hpp"
#include "keymesh/generate/unstructured/contour_tets.hpp"
#include "not_on_gpu.hpp"

namespace keymesh::backend {

SurfaceMesh contour(const ImageGrid& grid, const generate::ContourOptions& options, generate::ContourStats* stats,
                    std::vector<std::uint64_t>* point_keys) {
  if (options.backend != generate::Backend::Cuda) return generate::contour(grid, options, stats, point_keys);
  // The input is refused as the CPU refuses it, before the GPU is asked for.
  generate::check_contour_input(grid, options);
  if (options.total_planes || options.position_offset[0] || options.position_offset[1] || options.position_offset[2])
    throw InputError("--backend cuda: streamed (slab) or block contouring is not available on the GPU yet");
  // (options.history is refused by cuda::contour, by name.)
  if (point_keys && !options.history)
    throw InputError("--backend cuda: point keys are not available on the GPU yet (use --backend cpu)");
  return cuda::contour(grid, options, stats);
}

SurfaceMesh contour(const UnstructuredGrid& tets, const generate::ContourOptions& options,
                    generate::ContourStats* stats, std::vector<std::uint64_t>* point_keys) {
  if (options.backend != generate::Backend::Cuda) return generate::contour(tets, options, stats, point_keys);
  generate::check_tet_contour_input(tets, options);
  if (options.weld == generate::ContourWeld::VertexWeld) not_on_gpu("VERTEX-WELD (--weld vertexweld)");
  if (options.coarsen) not_on_gpu("coarsening (--coarsen)");
  if (options.history) not_on_gpu("per-point history (--history)");
  if (point_keys) not_on_gpu("point keys");
  return cuda::contour_tets(tets, options, stats);
}

}  // namespace keymesh::backend
