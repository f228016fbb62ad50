#pragma once
// PlaneSource: the z-planes of a volume, read on demand. io implements it
// (raw, NRRD, NIfTI, Zarr, DICOM: keymesh/io/plane_source.hpp) and generate
// consumes it (streamed contour: keymesh/generate/contour/contour_stream.hpp) and so
// does distributed; it lives here, below all three, so none includes another.
#include <cstddef>

#include "keymesh/core/types.hpp"
#include "keymesh/mesh/image_grid.hpp"

namespace keymesh {

// Planes of a volume read on demand (x fastest, native byte order).
class PlaneSource {
 public:
  virtual ~PlaneSource() = default;
  // dims, type, spacing, origin and name of the volume; no samples.
  virtual const ImageGrid& header() const = 0;
  // Reads planes [first, first + count) into out (count * nx * ny samples).
  virtual void read_planes(Id first, Id count, std::byte* out) = 0;
};

}  // namespace keymesh
