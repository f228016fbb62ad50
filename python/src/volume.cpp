// keymesh.Volume: a voxel grid owned by the module (what read() returns), its
// samples visible as a writable numpy view. contour() reads it in place.
#include <algorithm>
#include <cstring>

#include "common.hpp"

namespace keymesh::python {

std::array<double, 3> triple(const py::handle& obj, const char* what) {
  std::vector<double> v;
  try {
    v = obj.cast<std::vector<double>>();
  } catch (const py::cast_error&) {
    throw py::type_error(std::string(what) + " must be a sequence of 3 numbers");
  }
  if (v.size() != 3) throw py::value_error(std::string(what) + " must have 3 entries, got " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

namespace {

py::tuple as_tuple(const std::array<double, 3>& a) { return py::make_tuple(a[0], a[1], a[2]); }

std::shared_ptr<Volume> zeros(const py::handle& shape, const py::handle& dtype, const py::handle& spacing,
                              const py::handle& origin, const std::string& name) {
  const std::vector<Id> dims = integer_sequence(shape, "Volume shape");
  if (dims.size() != 3) throw py::value_error("Volume shape must have 3 entries (nx, ny, nz)");
  const ScalarType type = scalar_type_of(py::dtype::from_args(py::reinterpret_borrow<py::object>(dtype)), "Volume");
  auto v = std::make_shared<Volume>();
  v->grid.spacing = triple(spacing, "spacing");
  v->grid.origin = triple(origin, "origin");
  check_float32_geometry({dims[0], dims[1], dims[2]}, v->grid.origin, v->grid.spacing, "Volume");
  const long double bytes = static_cast<long double>(dims[0]) * static_cast<long double>(dims[1]) *
                            static_cast<long double>(dims[2]) * static_cast<long double>(scalar_size(type));
  try {
    v->grid.allocate({dims[0], dims[1], dims[2]}, type);
  } catch (const std::bad_alloc&) {
    throw OutOfMemory("out of memory: a Volume of shape (" + std::to_string(dims[0]) + ", " + std::to_string(dims[1]) +
                      ", " + std::to_string(dims[2]) + ") " + scalar_type_name(type) + " needs " + size_text(bytes));
  }
  v->grid.name = name;
  return v;
}

// A new spacing or origin, checked with the other as the volume readers check
// a file's (check_float32_geometry): every point finite in float32.
void set_geometry(Volume& v, const py::handle& value, bool spacing) {
  std::array<double, 3> s = v.grid.spacing, o = v.grid.origin;
  (spacing ? s : o) = triple(value, spacing ? "spacing" : "origin");
  check_float32_geometry(v.grid.dims, o, s, spacing ? "Volume.spacing" : "Volume.origin");
  v.grid.spacing = s;
  v.grid.origin = o;
}

}  // namespace

void register_volume(py::module_& m) {
  py::class_<Volume, std::shared_ptr<Volume>>(m, "Volume", R"doc(
A voxel volume owned by keymesh: what keymesh.read() returns for .vti, .nrrd,
.nii, .den and .raw files, and what contour() reads without copying.

``array`` is a writable numpy view of the samples with shape (nx, ny, nz):
axis 0 is x, 1 is y, 2 is z, in Fortran (x fastest) memory order, so
``array[i, j, k]`` is the sample at ``origin + (i, j, k) * spacing``. The view
keeps the Volume alive.

Volume(array, spacing=(1, 1, 1), origin=(0, 0, 0), name="scalars") copies a
3-D numpy array once (axis 0 = x); Volume.zeros(shape, dtype) allocates one to
fill in place. Spacing and origin are checked as a file's are, when given and
when set: every sample's position finite in float32 (keymesh.Error otherwise).
)doc")
      .def(py::init([](const py::array& array, const py::handle& spacing, const py::handle& origin,
                       const std::string& name) {
             if (array.ndim() != 3)
               throw py::value_error("Volume needs a 3-D array, got ndim=" + std::to_string(array.ndim()));
             auto v = zeros(py::make_tuple(array.shape(0), array.shape(1), array.shape(2)), array.dtype(), spacing,
                            origin, name);
             // numpy copies with any strides and byte order into the Fortran view
             // (a base that owns nothing: the grid outlives the temporary view).
             grid_view(v->grid, py::capsule(v.get(), [](void*) {})).attr("__setitem__")(py::ellipsis(), array);
             return v;
           }),
           py::arg("array"), py::arg("spacing") = py::make_tuple(1.0, 1.0, 1.0),
           py::arg("origin") = py::make_tuple(0.0, 0.0, 0.0), py::arg("name") = "scalars")
      .def_static("zeros", &zeros, py::arg("shape"), py::arg("dtype") = "float32",
                  py::arg("spacing") = py::make_tuple(1.0, 1.0, 1.0), py::arg("origin") = py::make_tuple(0.0, 0.0, 0.0),
                  py::arg("name") = "scalars",
                  "A zero-filled Volume of shape (nx, ny, nz) and the given dtype, to fill through .array.")
      .def_property_readonly(
          "array", [](py::object self) { return grid_view(self.cast<Volume&>().grid, self); },
          "The samples: a writable (nx, ny, nz) numpy view, axis 0 = x (keeps the Volume alive).")
      .def_property_readonly("shape", [](const Volume& v) { return py::make_tuple(v.grid.dims[0], v.grid.dims[1], v.grid.dims[2]); },
                             "(nx, ny, nz)")
      .def_property_readonly("dtype", [](const Volume& v) { return dtype_of(v.grid.type); }, "numpy dtype of the samples")
      .def_property(
          "spacing", [](const Volume& v) { return as_tuple(v.grid.spacing); },
          [](Volume& v, const py::handle& s) { set_geometry(v, s, true); }, "voxel size along x, y, z")
      .def_property(
          "origin", [](const Volume& v) { return as_tuple(v.grid.origin); },
          [](Volume& v, const py::handle& o) { set_geometry(v, o, false); }, "position of sample (0, 0, 0)")
      .def_property(
          "name", [](const Volume& v) { return v.grid.name; }, [](Volume& v, const std::string& n) { v.grid.name = n; },
          "name of the scalar field (contour's point_data key)")
      .def("__repr__", [](const Volume& v) {
        return "keymesh.Volume(shape=(" + std::to_string(v.grid.dims[0]) + ", " + std::to_string(v.grid.dims[1]) +
               ", " + std::to_string(v.grid.dims[2]) + "), dtype=" + scalar_type_name(v.grid.type) + ", spacing=" +
               std::string(py::repr(as_tuple(v.grid.spacing))) + ", origin=" +
               std::string(py::repr(as_tuple(v.grid.origin))) + ")";
      });
}

}  // namespace keymesh::python
