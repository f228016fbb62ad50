#include "keymesh/backend/labels.hpp"

#include "keymesh/cuda/surfaces.hpp"
#include "keymesh/generate/labels/labels_device.hpp"

namespace keymesh::backend {

SurfaceMesh contour_labels(const ImageGrid& grid, const generate::LabelOptions& options, generate::Backend backend,
                           generate::LabelStats* stats, std::vector<std::uint64_t>* history_key) {
  if (backend != generate::Backend::Cuda) return generate::contour_labels(grid, options, stats, history_key);
  generate::check_labels_input(grid, options);
  generate::check_device_label_options(options);
  return cuda::contour_labels(grid, options, stats);
}

}  // namespace keymesh::backend
