#pragma once
// Label surface nets on the backend the caller names: generate::contour_labels
// (CPU threads) or cuda::contour_labels (an NVIDIA GPU, the same bits), chosen
// above both as for the contour (backend/contour.hpp).
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/labels/labels.hpp"

namespace keymesh::backend {

// Backend::Cpu: generate::contour_labels. Backend::Cuda: its input checks
// that need no scan (generate::check_labels_input, the same InputError), then
// what the device path lacks refused by name (generate::check_device_label_options:
// --method discrete-mc, --per-label, --coarsen, --history; "(use --backend
// cpu)"), then cuda::contour_labels (InputError naming --backend cpu without
// a usable GPU).
SurfaceMesh contour_labels(const ImageGrid& grid, const generate::LabelOptions& options, generate::Backend backend,
                           generate::LabelStats* stats = nullptr, std::vector<std::uint64_t>* history_key = nullptr);

}  // namespace keymesh::backend
