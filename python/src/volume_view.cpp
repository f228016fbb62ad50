// A numpy volume seen as the library's ImageGrid without copying where its
// layout allows: the checks, byte order and axis order every function that
// takes a numpy volume (contour, tetrahedralize, contour_labels) needs.
#include "common.hpp"

namespace keymesh::python {

ArrayVolume view_array_volume(const py::object& volume, const py::object& spacing, const py::object& origin,
                              VolumeOrder order, const char* not_an_array) {
  ArrayVolume v;
  v.array = py::array::ensure(volume);
  if (!v.array) throw py::type_error(not_an_array);
  if (v.array.ndim() != 3)
    throw py::value_error("volume must be 3-D (axis 0 = x), got ndim=" + std::to_string(v.array.ndim()));
  v.grid.type = scalar_type_of(v.array.dtype(), "volume");
  if (!v.array.dtype().attr("isnative").cast<bool>())
    v.array = v.array.attr("astype")(v.array.dtype().attr("newbyteorder")("="));
  const int flags = v.array.flags();
  const bool fortran = (flags & py::array::f_style) && !(flags & py::array::c_style);
  if (order == VolumeOrder::CAsReversedAxes && !fortran) {
    v.array = py::array::ensure(v.array, py::array::c_style);
    v.reversed = true;
  } else {
    v.array = py::array::ensure(v.array, py::array::f_style);
  }
  const std::array<double, 3> s = spacing.is_none() ? std::array<double, 3>{1, 1, 1} : triple(spacing, "spacing");
  const std::array<double, 3> o = origin.is_none() ? std::array<double, 3>{0, 0, 0} : triple(origin, "origin");
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
