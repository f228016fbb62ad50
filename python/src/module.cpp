// keymesh._keymesh: the compiled half of the Python package `keymesh`
// (python/keymesh/__init__.py wraps it with Mesh and the conversions).
#include "common.hpp"

#include "keymesh/core/error.hpp"
#include "keymesh/core/retained_blocks.hpp"

namespace keymesh::python {

PythonProgress::PythonProgress(py::object callback) : callback_(std::move(callback)) {
  if (!callback_.is_none() && !PyCallable_Check(callback_.ptr()))
    throw py::type_error("progress must be callable as progress(stage, fraction), got " +
                         std::string(py::str(py::type::of(callback_).attr("__name__"))));
}

void PythonProgress::operator()(const char* stage, double fraction) const {
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  if (!callback_.is_none()) callback_(stage, fraction);
}

progress::ScopedHook PythonProgress::install() const {
  return progress::ScopedHook([this](const char* stage, double fraction) {
    py::gil_scoped_acquire gil;
    (*this)(stage, fraction);
  });
}

void check_threads(int threads) {
  if (threads < 0) throw py::value_error("threads must be >= 0 (0 = all cores), got " + std::to_string(threads));
}

ScalarType scalar_type_of(const py::dtype& dtype, const char* what) {
  const char kind = dtype.kind();
  const auto size = dtype.itemsize();
  if (kind == 'u' && size == 1) return ScalarType::UInt8;
  if (kind == 'i' && size == 1) return ScalarType::Int8;
  if (kind == 'u' && size == 2) return ScalarType::UInt16;
  if (kind == 'i' && size == 2) return ScalarType::Int16;
  if (kind == 'i' && size == 4) return ScalarType::Int32;
  if (kind == 'f' && size == 4) return ScalarType::Float32;
  if (kind == 'f' && size == 8) return ScalarType::Float64;
  const bool wide = (kind == 'u' && size == 4) || ((kind == 'i' || kind == 'u') && size == 8);
  throw py::type_error(std::string(what) + " has dtype " + dtype_name(dtype) +
                       "; keymesh supports uint8, int8, uint16, int16, int32, float32 and float64 " +
                       (wide ? "(label maps of this type: contour_labels; convert with .astype(numpy.float64) "
                               "for a contour)"
                             : "(convert with .astype(numpy.float32) for example)"));
}

ScalarType label_scalar_type_of(const py::dtype& dtype, const char* what) {
  const char kind = dtype.kind();
  const auto size = dtype.itemsize();
  if (kind == 'u' && size == 4) return ScalarType::UInt32;
  if (kind == 'i' && size == 8) return ScalarType::Int64;
  if (kind == 'u' && size == 8) return ScalarType::UInt64;
  return scalar_type_of(dtype, what);
}

py::dtype dtype_of(ScalarType type) { return py::dtype(scalar_type_name(type)); }

py::array grid_view(const ImageGrid& grid, py::handle owner) {
  const auto size = static_cast<py::ssize_t>(scalar_size(grid.type));
  std::vector<py::ssize_t> shape{grid.dims[0], grid.dims[1], grid.dims[2]};
  std::vector<py::ssize_t> strides{size, size * grid.dims[0], size * grid.dims[0] * grid.dims[1]};
  return py::array(dtype_of(grid.type), std::move(shape), std::move(strides), grid.data(), owner);
}

void register_errors(py::module_& m) {
  static py::exception<InputError> error(m, "Error", PyExc_ValueError);
  static py::exception<LimitError> limit(m, "LimitError", error.ptr());
  error.doc() = "Bad input for keymesh (a file, an array, an argument); a ValueError.";
  limit.doc() = "A request past a keymesh limit (e.g. more than 2^32 - 1 output points); a keymesh.Error.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const LimitError& e) {
      limit(e.what());
    } catch (const InputError& e) {
      error(e.what());
    }
  });
  // Out of memory: MemoryError, named where the module allocates itself
  // (OutOfMemory), the library's own allocations by what was running. Local
  // to this module: other extensions keep pybind11's translation.
  py::register_local_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const OutOfMemory& e) {
      PyErr_SetString(PyExc_MemoryError, e.what());
    } catch (const std::bad_alloc&) {
      PyErr_SetString(PyExc_MemoryError,
                      "out of memory: keymesh could not allocate its working arrays (std::bad_alloc); "
                      "a smaller input, or more memory");
    }
  });
}

void register_labels(py::module_& m);  // labels.cpp
void register_dask_contour_block(py::module_& m);  // dask_contour_block.cpp
void register_dask_contour_merge(py::module_& m);  // dask_contour_merge.cpp
void register_dask_labels(py::module_& m);         // dask_labels.cpp
void register_labels_precomputed(py::module_& m);  // labels_precomputed.cpp

}  // namespace keymesh::python

PYBIND11_MODULE(_keymesh, m) {
  namespace kp = keymesh::python;
  m.doc() = "keymesh's compiled core (use the `keymesh` package, which wraps it).";
  // Each file's bindings, the error types first.
  for (auto* add : {&kp::register_errors, &kp::register_volume, &kp::register_contour, &kp::register_key_reduce,
                    &kp::register_io, &kp::register_check, &kp::register_marching_cubes, &kp::register_operations,
                    &kp::register_labels, &kp::register_dask_contour_block, &kp::register_dask_contour_merge,
                    &kp::register_dask_labels, &kp::register_labels_precomputed, &kp::register_contour_device})
    add(m);
  m.def("thread_count", &keymesh::parallel::thread_count,
        "Worker threads the library uses when a call passes threads=0 (all cores).");
  m.def("release_memory", &keymesh::retained_blocks::release_all,
        "Unmaps the large blocks kept from freed outputs for the next call's outputs; returns their bytes.");
  m.def("retained_memory", [] {
    const auto s = keymesh::retained_blocks::stats();
    pybind11::dict d;
    d["kept_bytes"] = s.kept_bytes, d["kept_blocks"] = s.kept_blocks, d["reused"] = s.reused, d["mapped"] = s.mapped;
    d["limit_bytes"] = keymesh::retained_blocks::limit(), d["limit_seconds"] = keymesh::retained_blocks::limit_seconds();
    return d;
  }, "The blocks kept for reuse: bytes, count, acquisitions served by a kept block and by a fresh mapping, limits.");
}
