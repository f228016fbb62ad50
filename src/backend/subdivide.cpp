#include "keymesh/backend/subdivide.hpp"

#include "keymesh/cuda/unstructured.hpp"
#include "not_on_gpu.hpp"

namespace keymesh::backend {

namespace {

// What the GPU's subdivision lacks, refused once the input has passed the CPU's checks.
void refuse_on_gpu(const generate::SubdivideOptions& options) {
  if (options.weld != generate::SubdivideWeld::KeyReduce) not_on_gpu("VERTEX-WELD (--weld vertexweld)");
}

}  // namespace

SurfaceMesh subdivide(const SurfaceMesh& mesh, const generate::SubdivideOptions& options, generate::Backend backend) {
  if (backend != generate::Backend::Cuda) return generate::subdivide(mesh, options);
  generate::check_subdivide_input(mesh, options);
  refuse_on_gpu(options);
  return cuda::subdivide(mesh, options);
}

UnstructuredGrid subdivide(const UnstructuredGrid& tets, const generate::SubdivideOptions& options,
                           generate::Backend backend) {
  if (backend != generate::Backend::Cuda) return generate::subdivide(tets, options);
  generate::check_subdivide_input(tets, options);
  refuse_on_gpu(options);
  return cuda::subdivide(tets, options);
}

}  // namespace keymesh::backend
