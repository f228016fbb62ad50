// Python inputs converted with every failure named: numpy copies whose
// allocation is checked (never the null array pybind11's ensure() leaves,
// which the next use turns into a segfault), integers past 64 bits, paths
// holding a NUL byte.
#include <cmath>
#include <limits>

#include "common.hpp"

namespace keymesh::python {

std::string shape_text(const std::vector<py::ssize_t>& shape) {
  std::string s = "(";
  for (std::size_t d = 0; d < shape.size(); ++d) s += (d ? ", " : "") + std::to_string(shape[d]);
  return s + (shape.size() == 1 ? ",)" : ")");
}

std::string shape_text(const py::array& a) {
  return shape_text(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()));
}

namespace {

bool has_layout(const py::array& a, int flags) {
  const int f = a.flags();
  return (flags & py::array::c_style) ? (f & py::array::c_style) != 0 : (f & py::array::f_style) != 0;
}

// "a C-ordered float32 copy of volume (shape (700, 700, 700), 1.28 GiB)"
std::string copy_text(const py::array& a, const py::dtype& dtype, int flags, const char* what, long double bytes) {
  return std::string((flags & py::array::c_style) ? "a C-ordered " : "a Fortran-ordered ") + dtype_name(dtype) +
         " copy of " + what + " (shape " + shape_text(a) + ", " + size_text(bytes) + ")";
}

}  // namespace

py::array converted_array(const py::array& a, const py::dtype& dtype, int flags, const char* what) {
  const py::dtype native = dtype.attr("newbyteorder")("=");
  if (a.dtype().equal(native) && has_layout(a, flags)) return a;
  // numpy's sizes are ssize_t: a view with zero strides can claim more
  // samples than a copy could ever hold (2^62 float32 are 2^64 bytes).
  const long double bytes = static_cast<long double>(a.size()) * static_cast<long double>(native.itemsize());
  if (bytes > static_cast<long double>(std::numeric_limits<py::ssize_t>::max()))
    throw OutOfMemory("out of memory: " + copy_text(a, native, flags, what, bytes) +
                      " would pass the address space");
  // Imported per call (a lookup in sys.modules): a static py::object would
  // be released after the interpreter is gone, crashing it at exit.
  const py::module_ numpy = py::module_::import("numpy");
  try {
    return numpy.attr((flags & py::array::c_style) ? "ascontiguousarray" : "asfortranarray")(a, native);
  } catch (py::error_already_set& e) {
    if (e.matches(PyExc_MemoryError))
      throw OutOfMemory("out of memory: cannot allocate " + copy_text(a, native, flags, what, bytes));
    if (e.matches(PyExc_KeyboardInterrupt)) throw;
    return py::reinterpret_steal<py::array>(py::handle());  // not convertible: the caller names it
  }
}

std::vector<Id> integer_sequence(const py::handle& obj, const char* what) {
  if (!py::isinstance<py::sequence>(obj) || py::isinstance<py::str>(obj))
    throw py::type_error(std::string(what) + " must be a sequence of integers");
  std::vector<Id> out;
  for (const py::handle item : obj.cast<py::sequence>()) {
    if (PyBool_Check(item.ptr()) || !PyIndex_Check(item.ptr()))
      throw py::type_error(std::string(what) + " must hold integers, got " +
                           std::string(py::str(py::type::of(item).attr("__name__"))));
    const py::int_ value = py::reinterpret_steal<py::int_>(PyNumber_Index(item.ptr()));
    if (!value) throw py::error_already_set();
    int overflow = 0;
    const long long v = PyLong_AsLongLongAndOverflow(value.ptr(), &overflow);
    if (overflow != 0) {
      const auto bits = value.attr("bit_length")().cast<long long>();
      PyErr_Format(PyExc_OverflowError, "%s[%zu] is past the 64-bit integer range (a %lld-bit integer)", what,
                   out.size(), bits);
      throw py::error_already_set();
    }
    if (v == -1 && PyErr_Occurred()) throw py::error_already_set();
    out.push_back(static_cast<Id>(v));
  }
  return out;
}

void refuse_nul_path(const std::string& path, const char* what) {
  const auto at = path.find('\0');
  if (at == std::string::npos) return;
  std::string shown;
  for (char c : path) shown += c == '\0' ? std::string("\\0") : std::string(1, c);
  throw py::value_error(std::string(what) + ": the path '" + shown + "' holds a NUL byte at position " +
                        std::to_string(at) + "; a file name cannot contain one");
}

}  // namespace keymesh::python
