// A numpy volume seen as the library's ImageGrid without copying where its
// layout allows: the checks, byte order and axis order every function that
// takes a numpy volume (contour, tetrahedralize, contour_labels) needs.
#include "common.hpp"

namespace keymesh::python {

// Axes named the way the Python docs name them (axis 0 is x, whatever the
// memory order): the library would name a C-ordered array's axis 0 "z",
// the grid's axis it becomes.
void check_volume_shape(const std::vector<py::ssize_t>& shape, const VolumeUse& use) {
  for (int a = 0; a < 3; ++a)
    if (shape[a] < use.min_samples)
      throw InputError(std::string(use.command) + ": volume has shape " + shape_text(shape) + ": " +
                       std::to_string(shape[a]) + " sample(s) along axis " + std::to_string(a) + " (" + "xyz"[a] +
                       "), need at least " + std::to_string(use.min_samples));
}

void check_volume_geometry(const ImageGrid& grid, const char* command) {
  check_float32_geometry(grid.dims, grid.origin, grid.spacing, command);
}

ArrayVolume view_array_volume(const py::object& volume, const py::object& spacing, const py::object& origin,
                              VolumeOrder order, const VolumeUse& use) {
  ArrayVolume v;
  v.array = py::array::ensure(volume);
  if (!v.array) throw py::type_error(use.not_an_array);
  if (v.array.ndim() != 3)
    throw py::value_error("volume must be 3-D (axis 0 = x), got ndim=" + std::to_string(v.array.ndim()));
  v.grid.type = use.label_map ? label_scalar_type_of(v.array.dtype(), "volume") : scalar_type_of(v.array.dtype(), "volume");
  check_volume_shape({v.array.shape(0), v.array.shape(1), v.array.shape(2)}, use);
  const std::array<double, 3> s = spacing.is_none() ? std::array<double, 3>{1, 1, 1} : triple(spacing, "spacing");
  const std::array<double, 3> o = origin.is_none() ? std::array<double, 3>{0, 0, 0} : triple(origin, "origin");
  // Along the array's axes (x = axis 0), before anything is copied.
  check_float32_geometry({v.array.shape(0), v.array.shape(1), v.array.shape(2)}, o, s, use.command);
  const int flags = v.array.flags();
  const bool fortran = (flags & py::array::f_style) && !(flags & py::array::c_style);
  v.reversed = order == VolumeOrder::CAsReversedAxes && !fortran;
  v.array = converted_array(v.array, v.array.dtype(), v.reversed ? py::array::c_style : py::array::f_style, "volume");
  if (!v.array) throw py::type_error(use.not_an_array);
  for (int a = 0; a < 3; ++a) {
    const int from = v.reversed ? 2 - a : a;
    v.grid.dims[a] = v.array.shape(from);
    v.grid.spacing[a] = s[from];
    v.grid.origin[a] = o[from];
  }
  v.grid.external = static_cast<const std::byte*>(v.array.data());
  return v;
}

}  // namespace keymesh::python
