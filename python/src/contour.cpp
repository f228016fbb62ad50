// keymesh.contour: marching cubes welded by KEY-REDUCE, over a numpy volume or
// a keymesh.Volume.
//
// Axis convention: array axis 0 is x (the first coordinate of the points),
// like scikit-image's marching_cubes. The library's grid is x-fastest in
// memory, so
//  - a Fortran-ordered array (or a Volume) is the grid as it is;
//  - a C-ordered array (numpy's default: axis 2 fastest) is contoured as the
//    grid with the axes reversed, and the output is mirrored back (x and z
//    swapped in points and normals, two corners of every triangle swapped so
//    that triangles still face lower values);
//  - any other layout is first made C-contiguous by numpy.
// The library's ImageGrid owns its samples, so a numpy array is copied once
// (one memcpy); a Volume is read in place.
#include <chrono>
#include <cmath>
#include <cstring>
#include <optional>


#include "common.hpp"
#include "keymesh/generate/contour.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::python {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

generate::ContourNormals parse_normals(const std::string& s) {
  if (s == "none") return generate::ContourNormals::None;
  if (s == "gradient") return generate::ContourNormals::Gradient;
  if (s == "average") return generate::ContourNormals::Average;
  throw py::value_error("normals must be 'none', 'gradient' or 'average', got '" + s + "'");
}

generate::ContourWeld parse_weld(const std::string& s) {
  if (s == "keyreduce") return generate::ContourWeld::KeyReduce;
  if (s == "keyreduce-sort") return generate::ContourWeld::KeyReduceSort;
  if (s == "vertexweld") return generate::ContourWeld::VertexWeld;
  throw py::value_error("weld must be 'keyreduce', 'keyreduce-sort' or 'vertexweld', got '" + s + "'");
}

// Mirrors a mesh contoured over the reversed axes back: x <-> z.
void swap_x_z(SurfaceMesh& mesh) {
  float* p = mesh.points.data();
  parallel::for_each(mesh.num_points(), [p](Id i) { std::swap(p[3 * i], p[3 * i + 2]); });
  for (Field& f : mesh.point_fields) {
    if (f.components != 3) continue;
    float* v = f.values.data();
    parallel::for_each(mesh.num_points(), [v](Id i) { std::swap(v[3 * i], v[3 * i + 2]); });
  }
  PointIndex* c = mesh.connectivity.data();
  parallel::for_each(mesh.num_cells(), [c](Id t) { std::swap(c[3 * t + 1], c[3 * t + 2]); });
}

py::tuple contour(const py::object& volume, const std::vector<double>& isovalues, const py::object& spacing,
                  const py::object& origin, const std::string& normals, const std::string& weld, bool coarsen,
                  bool curvature, int threads, const py::object& callback) {
  check_threads(threads);
  const PythonProgress progress(callback);
  if (isovalues.empty()) throw py::value_error("iso: give at least one isovalue");
  for (double v : isovalues)
    if (!std::isfinite(v)) throw py::value_error("iso must be finite, got " + std::string(py::repr(py::float_(v))));
  generate::ContourOptions opt;
  opt.isovalues = isovalues;
  opt.normals = parse_normals(normals);
  opt.weld = parse_weld(weld);
  opt.coarsen = coarsen;
  opt.curvature = curvature;

  const ImageGrid* grid = nullptr;
  ImageGrid copy;
  bool reversed = false;
  py::array array;  // keeps a converted array alive while the GIL is released
  if (py::isinstance<Volume>(volume)) {
    grid = &volume.cast<Volume&>().grid;
    if ((!spacing.is_none() && triple(spacing, "spacing") != grid->spacing) ||
        (!origin.is_none() && triple(origin, "origin") != grid->origin))
      throw py::value_error("contour: a Volume carries its own spacing and origin; set volume.spacing / "
                            "volume.origin instead of passing different ones");
  } else {
    array = py::array::ensure(volume);
    if (!array) throw py::type_error("volume must be a 3-D numpy array or a keymesh.Volume");
    if (array.ndim() != 3)
      throw py::value_error("volume must be 3-D (axis 0 = x), got ndim=" + std::to_string(array.ndim()));
    copy.type = scalar_type_of(array.dtype(), "volume");
    if (array.dtype().attr("isnative").cast<bool>() == false)
      array = array.attr("astype")(array.dtype().attr("newbyteorder")("="));
    const bool fortran = (array.flags() & py::array::f_style) && !(array.flags() & py::array::c_style);
    if (!fortran) array = py::array::ensure(array, py::array::c_style);
    reversed = !fortran;
    const std::array<double, 3> s = spacing.is_none() ? std::array<double, 3>{1, 1, 1} : triple(spacing, "spacing");
    const std::array<double, 3> o = origin.is_none() ? std::array<double, 3>{0, 0, 0} : triple(origin, "origin");
    for (int a = 0; a < 3; ++a) {
      const int from = reversed ? 2 - a : a;
      copy.dims[a] = array.shape(from);
      copy.spacing[a] = s[from];
      copy.origin[a] = o[from];
    }
    grid = &copy;
  }

  py::dict info;
  SurfaceMesh mesh;
  generate::ContourStats stats;
  double copy_s = 0, contour_s = 0, mirror_s = 0;
  {
    py::gil_scoped_release release;
    ThreadScope scope(threads);
    auto hook = progress.install();
    progress::report("contour", 0.0);
    auto t0 = Clock::now();
    // The array's memory is read in place (C- or Fortran-contiguous, native
    // byte order by now); `array` keeps it alive until the call returns.
    if (grid == &copy) copy.external = static_cast<const std::byte*>(array.data());
    copy_s = seconds_since(t0);
    t0 = Clock::now();
    mesh = generate::contour(*grid, opt, &stats);
    contour_s = seconds_since(t0);
    t0 = Clock::now();
    if (reversed) swap_x_z(mesh);
    mirror_s = seconds_since(t0);
    progress::report("contour", 1.0);
    copy.bytes = {};
  }
  info["copy"] = copy_s;
  info["contour"] = contour_s;
  info["mirror"] = mirror_s;
  info["classify"] = stats.classify;
  info["generate"] = stats.generate;
  info["weld"] = stats.weld;
  info["fields"] = stats.fields;
  info["coarsen"] = stats.coarsen;
  info["triangles_before_coarsening"] = stats.triangles_before_coarsening;
  info["key_bits"] = stats.key_bits;
  info["zero_copy"] = true;
  return py::make_tuple(mesh_to_python(std::move(mesh)), info);
}

}  // namespace

void register_contour(py::module_& m) {
  m.def("contour", &contour, py::arg("volume"), py::arg("isovalues"), py::arg("spacing") = py::none(),
        py::arg("origin") = py::none(), py::arg("normals") = "average", py::arg("weld") = "keyreduce",
        py::arg("coarsen") = false, py::arg("curvature") = false, py::arg("threads") = 0,
        py::arg("progress") = py::none(),
        "Marching cubes welded by KEY-REDUCE; returns ((points, cells, offsets, point_data), timings). "
        "Use keymesh.contour, which wraps this in a Mesh.");
}

}  // namespace keymesh::python
