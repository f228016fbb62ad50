#pragma once
// Shared helpers of the Python module: numpy arrays that adopt std::vectors,
// the thread-count scope, dtype mapping, and the registration functions of
// each file (one file per concept).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/progress.hpp"
#include "keymesh/core/work_estimate.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"
#include "keymesh/parallel/threads.hpp"

namespace keymesh::generate {
struct LabelOptions;    // keymesh/generate/labels/labels.hpp
struct ContourOptions;  // keymesh/generate/contour/contour.hpp
}  // namespace keymesh::generate

namespace keymesh::python {

namespace py = pybind11;

// A numpy array of `shape` that takes over v's buffer without copying: the
// vector moves to the heap and a capsule, the array's base, deletes it when
// the last view goes. `View` lets the bytes be read as another type of the
// same size (uint64 keys shown as int64).
template <class View = void, class T, class A>
py::array adopt(std::vector<T, A>&& v, std::vector<py::ssize_t> shape) {
  using V = std::conditional_t<std::is_void_v<View>, T, View>;
  static_assert(sizeof(V) == sizeof(T));
  auto* owned = new std::vector<T, A>(std::move(v));
  py::capsule base(owned, [](void* p) { delete static_cast<std::vector<T, A>*>(p); });
  return py::array_t<V>(std::move(shape), reinterpret_cast<const V*>(owned->data()), base);
}

// Sets the library's (process-wide) worker count for one call, restores it
// after. threads: 0 = all cores; negative is refused before this is built.
class ThreadScope {
 public:
  explicit ThreadScope(int threads) : previous_(parallel::thread_count()) { parallel::set_thread_count(threads); }
  ~ThreadScope() { parallel::set_thread_count(previous_); }
  ThreadScope(const ThreadScope&) = delete;
  ThreadScope& operator=(const ThreadScope&) = delete;

 private:
  int previous_;
};

// The library's progress hook for one call, made while the GIL is held and
// installed (on the calling thread) once it is released: at every stage the
// library reports, it takes the GIL back, checks for signals (Ctrl-C raises
// KeyboardInterrupt: the C++ call unwinds and the exception reaches Python)
// and calls the user's progress(stage, fraction) if one was given; an
// exception from the callback abandons the call the same way.
class PythonProgress {
 public:
  explicit PythonProgress(py::object callback);
  // Reports the stage from the GIL-holding side (before or after a call).
  void operator()(const char* stage, double fraction) const;
  // Installs the hook; construct inside the gil_scoped_release block.
  progress::ScopedHook install() const;

 private:
  py::object callback_;
};

// Runs f() the way every long call runs: the GIL released, `threads`
// workers (restored after), and, when given, the progress hook installed
// (Ctrl-C and progress= at every stage the library reports).
template <class F>
decltype(auto) run_released(int threads, F&& f) {
  py::gil_scoped_release release;
  ThreadScope scope(threads);
  return f();
}
template <class F>
decltype(auto) run_released(int threads, const PythonProgress& progress, F&& f) {
  py::gil_scoped_release release;
  ThreadScope scope(threads);
  auto hook = progress.install();
  return f();
}

// run_released for a library call that reports no stages itself: progress
// says (stage, 0) before f() and (stage, 1) after.
template <class F>
auto run_released_stage(int threads, const PythonProgress& progress, const char* stage, F&& f) {
  return run_released(threads, progress, [&] {
    progress::report(stage, 0.0);
    auto result = f();
    progress::report(stage, 1.0);
    return result;
  });
}

// The visitor that stores each (name, value) of analyze/ and
// generate/report_fields.hpp in `dict`: visit_fields(stats, into(dict)).
inline auto into(py::dict& dict) {
  return [&dict](const char* name, const auto& value) { dict[name] = value; };
}

// ValueError unless threads >= 0.
void check_threads(int threads);

// An allocation of the module's own that cannot be made: Python's
// MemoryError (register_errors), the message naming the array and its size.
class OutOfMemory : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `a` in `dtype` (native byte order) and the layout `flags` (py::array::
// c_style or f_style): `a` itself when it is already so, else numpy's copy.
// The copy's size is checked before it is asked for and a copy numpy cannot
// allocate raises OutOfMemory naming `what`, the shape, dtype and bytes:
// never the null array py::array::ensure() gives (every use of which would
// crash the interpreter). Other failures of the conversion (an object array
// of strings, ...) give the null array, for the caller's own message.
py::array converted_array(const py::array& a, const py::dtype& dtype, int flags, const char* what);
// The same for any object numpy takes as an array (a list, ...): null when
// it takes none. T and Flags as in py::array_t (forcecast: any numeric dtype).
template <class T, int Flags = py::array::c_style>
py::array_t<T, Flags> checked_array(const py::handle& obj, const char* what) {
  static_assert(Flags == py::array::c_style || Flags == py::array::f_style);
  const py::array a = py::array::ensure(obj);
  if (!a) return py::reinterpret_steal<py::array_t<T, Flags>>(py::handle());
  return py::reinterpret_steal<py::array_t<T, Flags>>(
      converted_array(a, py::dtype::of<T>(), Flags, what).release());
}
// "(700, 700, 700)"
std::string shape_text(const py::array& a);
std::string shape_text(const std::vector<py::ssize_t>& shape);
// A copy of the module's own (into a std::vector, a library Array): `fill`
// runs and a std::bad_alloc it throws becomes OutOfMemory naming `what` and
// the `bytes` it needed.
template <class F>
void allocating(const char* what, long double bytes, F&& fill) {
  try {
    fill();
  } catch (const std::bad_alloc&) {
    throw OutOfMemory(std::string("out of memory: the copy of ") + what + " needs " + size_text(bytes));
  }
}

// Python integers as the library's: OverflowError naming `what` past the
// 64-bit range, TypeError for a non-integer (pybind11's own cast would say
// neither which argument nor why).
std::vector<Id> integer_sequence(const py::handle& obj, const char* what);

// ValueError unless `path` holds no NUL byte: the file system would cut the
// name there (read a file other than the one named, or write one).
void refuse_nul_path(const std::string& path, const char* what);

// The library's scalar type of a numpy dtype; TypeError naming the dtype
// (and what is accepted) otherwise. `what` names the argument.
ScalarType scalar_type_of(const py::dtype& dtype, const char* what);
// The same, with the wide label types too (uint32, int64, uint64: label
// maps, which contour_labels and reads take).
ScalarType label_scalar_type_of(const py::dtype& dtype, const char* what);
py::dtype dtype_of(ScalarType type);
// "float32", ">f4", ...
inline std::string dtype_name(const py::dtype& dtype) { return py::str(static_cast<py::handle>(dtype)); }

// An ndarray view of the volume's samples: shape (nx, ny, nz), axis 0 = x,
// Fortran order (x varies fastest, as in the grid). `owner` keeps the grid alive.
py::array grid_view(const ImageGrid& grid, py::handle owner);

// A sequence of 3 numbers (spacing, origin); TypeError / ValueError naming `what`.
std::array<double, 3> triple(const py::handle& obj, const char* what);

// How a numpy volume (axis 0 = x) becomes the library's x-fastest grid:
//  - Fortran: a Fortran-ordered array is read in place, any other is copied
//    into that order once;
//  - CAsReversedAxes: a Fortran-ordered array is read in place, any other is
//    made C-contiguous (numpy's default: no copy) and read as the grid with
//    the axes reversed; the caller mirrors its output back (contour).
enum class VolumeOrder { Fortran, CAsReversedAxes };

// The grid over a numpy volume's samples: `array` holds them (keep it alive
// while `grid` is used), `reversed` says the grid's x is the array's axis 2.
struct ArrayVolume {
  ImageGrid grid;
  py::array array;
  bool reversed = false;
};
// What a function needs of a numpy volume: its name for messages, the
// samples it needs along every axis, the TypeError for a non-array.
struct VolumeUse {
  const char* command;
  Id min_samples;
  const char* not_an_array;
  bool label_map = false;  // the wide label types too (label_scalar_type_of)
};
// TypeError `not_an_array` when `volume` is no array, ValueError unless 3-D,
// TypeError for a dtype the library has no scalar type for, keymesh.Error
// for fewer than min_samples along an axis (named as the docs name it, axis
// 0 = x) or a geometry past float32 (check_float32_geometry, the check every
// volume reader makes); MemoryError when the copy a layout needs cannot be
// made. Spacing and origin (None: 1 and 0) are given along the array's axes.
ArrayVolume view_array_volume(const py::object& volume, const py::object& spacing, const py::object& origin,
                              VolumeOrder order, const VolumeUse& use);
// keymesh.Error (naming the axis as the docs name it, axis 0 = x) unless
// every axis of a 3-D volume's shape has use.min_samples samples.
void check_volume_shape(const std::vector<py::ssize_t>& shape, const VolumeUse& use);
// keymesh.Error unless a grid's points are finite in float32, checked where
// a Volume is used (its spacing and origin can be set after it was made).
void check_volume_geometry(const ImageGrid& grid, const char* command);

// Fields <-> a dict of numpy arrays, (rows,) for one component, (rows, k)
// otherwise: to_python moves the values (no copy); from_python copies them
// as float32, ValueError (naming `what`) unless each has `rows` rows.
py::dict fields_to_python(std::vector<Field>& fields, py::ssize_t rows);
std::vector<Field> fields_from_python(const py::object& data, py::ssize_t rows, const char* what);

// The label map a labels function reads (labels.cpp): a Volume's own grid
// (its geometry checked; spacing and origin are its own), or a view of a
// numpy array's samples in Fortran order, the wide label types too, kept in
// `view`. Errors as view_array_volume's, naming `command`.
const ImageGrid& label_grid(const py::object& volume, const py::object& spacing, const py::object& origin,
                            ArrayVolume& view, const char* command);
// contour_labels' arguments as the library's options (labels.cpp);
// ValueError for an unknown method.
generate::LabelOptions label_options(const std::string& method, const std::vector<std::int64_t>& labels,
                                     std::int64_t background, bool per_label, int smoothing_iterations,
                                     double relaxation, bool coarsen);
// point_data["history_key"] (uint64) added to mesh_to_python's parts when
// `history` (labels.cpp): contour_labels' and the Dask merge's.
py::tuple with_history_key(py::tuple parts, std::vector<std::uint64_t>&& history_key, bool history);

// keymesh.contour's arguments as the library's options (contour.cpp):
// ValueError for no isovalue, a non-finite one, an unknown normals, weld or
// backend name.
generate::ContourOptions contour_options(const std::vector<double>& isovalues, const std::string& normals,
                                         const std::string& weld, bool coarsen, bool curvature, bool scalars,
                                         const std::string& backend);

// Inside a catch block: rethrows the library's InputError or LimitError
// with the CLI's "--backend cuda" / "--backend cpu" said as Python says them
// (backend='cuda'), any other exception as it is (contour_device.cpp).
[[noreturn]] void rethrow_in_python_words();

// A mesh contoured over a C-ordered array's reversed axes (VolumeOrder::
// CAsReversedAxes) mirrored back into the array's frame: x <-> z in points
// and 3-component point fields, two corners of every triangle swapped so
// that it still faces lower values (contour.cpp).
void mirror_axes(SurfaceMesh& mesh);
// A C-ordered array's history_key (3 * grid point + axis + isovalue * 3N,
// docs/HISTORY.md) renumbered from the library's reversed axes, whose dims
// are library_dims, into the array's own (contour.cpp).
void keys_in_array_frame(std::vector<std::uint64_t>& keys, const std::array<Id, 3>& library_dims);

// SurfaceMesh <-> (points, cells, offsets, point_data, cell_data) of a Python Mesh.
// to_python moves every array into numpy without a copy; triangle meshes
// give cells of shape (m, 3) and offsets None, polygon meshes a flat
// connectivity array and offsets (m + 1).
py::tuple mesh_to_python(SurfaceMesh&& mesh);
// Copies (and converts) a Python Mesh's arrays; ValueError on bad shapes or ids.
SurfaceMesh mesh_from_python(const py::handle& mesh);

// UnstructuredGrid <-> (points, cells, offsets, cell_types, cell_type,
// point_data, cell_data) of a Python Grid; uniform grids give cells of shape
// (m, corners per cell) and offsets/cell_types None.
py::tuple grid_to_python(UnstructuredGrid&& grid);
UnstructuredGrid grid_from_python(const py::handle& grid);

// A volume owned by the module (keymesh.Volume): contour reads it without a copy.
struct Volume {
  ImageGrid grid;
};

void register_errors(py::module_& m);
void register_volume(py::module_& m);
void register_contour(py::module_& m);
void register_key_reduce(py::module_& m);
void register_io(py::module_& m);
void register_check(py::module_& m);
void register_marching_cubes(py::module_& m);
void register_operations(py::module_& m);
void register_contour_device(py::module_& m);

}  // namespace keymesh::python
