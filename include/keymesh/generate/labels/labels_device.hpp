#pragma once
// Label surface nets through the device path (the template over the device
// is src/generate/labels/labels_device.hpp, beside the label volume it
// reads): equal to contour_labels() bit for bit for the surface nets network
// (the default method, any smoothing, label selection and background).
// Refused by name (InputError): --method discrete-mc, --per-label,
// --coarsen.
#include "keymesh/generate/labels/labels.hpp"

namespace keymesh::generate {

// The options the device path lacks, refused by name.
void check_device_label_options(const LabelOptions& options);

// contour_labels() through the device path on the CPU device;
// `force_64bit_keys` welds with 64-bit cell keys where 32 bits would do
// (what a volume of more than 2^32 cells needs; tests use it).
SurfaceMesh contour_labels_on_cpu_device(const ImageGrid& grid, const LabelOptions& options,
                                         LabelStats* stats = nullptr, bool force_64bit_keys = false);

}  // namespace keymesh::generate
