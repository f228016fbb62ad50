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
// A contiguous array's samples and a Volume's are read in place
// (view_array_volume, volume_view.cpp).
#include <chrono>
#include <cmath>

#include "common.hpp"
#include "keymesh/backend/contour.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/option_names.hpp"
#include "keymesh/generate/report_fields.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"

namespace keymesh::python {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Mirrors n points (or 3-vectors) and m triangles contoured over the
// reversed axes back: x <-> z, and two corners of every triangle swapped so
// that it still faces lower values.
void swap_x_z(float* p, Id n) {
  parallel::for_each(n, [p](Id i) { std::swap(p[3 * i], p[3 * i + 2]); });
}
void swap_corners(PointIndex* c, Id m) {
  parallel::for_each(m, [c](Id t) { std::swap(c[3 * t + 1], c[3 * t + 2]); });
}

// The output of a contour with positions and triangles (and the scalar)
// only, in arrays the module allocates itself (ContourOptions::
// output_arrays): uninitialised until the contour writes them, as a
// SurfaceMesh's Arrays are; their storage is kept for the next call when
// the arrays are freed (core/retained_blocks.hpp).
struct OwnArrays {
  Id points = 0, triangles = 0;
  bool with_scalars = false;
  Array<float> xyz, scalars;
  Array<PointIndex> connectivity;

  generate::ContourArrays allocate(Id n, Id m, bool scalar) {
    points = n, triangles = m, with_scalars = scalar;
    parallel::resize_fresh(xyz, static_cast<std::size_t>(3 * n));
    parallel::resize_fresh(connectivity, static_cast<std::size_t>(3 * m));
    if (with_scalars) parallel::resize_fresh(scalars, static_cast<std::size_t>(n));
    return {xyz.data(), connectivity.data(), with_scalars ? scalars.data() : nullptr};
  }

  // (points, cells, None, point_data, cell_data), as mesh_to_python gives them.
  py::tuple to_python(const std::string& scalar_name) {
    py::dict point_data;
    if (with_scalars) point_data[py::str(scalar_name)] = adopt(std::move(scalars), {points});
    py::array p = adopt(std::move(xyz), {points, 3});
    return py::make_tuple(p, adopt(std::move(connectivity), {triangles, 3}), py::none(), point_data, py::dict());
  }
};

// The grid contour reads: a Volume's own, or a view of a numpy array's samples.
const ImageGrid& contour_grid(const py::object& volume, const py::object& spacing, const py::object& origin,
                              ArrayVolume& view) {
  if (!py::isinstance<Volume>(volume)) {
    view = view_array_volume(volume, spacing, origin, VolumeOrder::CAsReversedAxes,
                             {"contour", 2, "volume must be a 3-D numpy array or a keymesh.Volume"});
    return view.grid;
  }
  const ImageGrid& grid = volume.cast<Volume&>().grid;
  check_volume_geometry(grid, "contour");
  if ((!spacing.is_none() && triple(spacing, "spacing") != grid.spacing) ||
      (!origin.is_none() && triple(origin, "origin") != grid.origin))
    throw py::value_error("contour: a Volume carries its own spacing and origin; set volume.spacing / "
                          "volume.origin instead of passing different ones");
  return grid;
}

// The seconds of each step and the contour's statistics (contour's second result).
py::dict contour_info(const generate::ContourStats& stats, double contour_s, double mirror_s) {
  py::dict info;
  info["copy"] = 0.0;  // the samples are read in place
  info["contour"] = contour_s;
  info["mirror"] = mirror_s;
  generate::visit_stage_seconds(stats, into(info));
  info["triangles_before_coarsening"] = stats.triangles_before_coarsening;
  info["key_bits"] = stats.key_bits;
  info["zero_copy"] = true;
  return info;
}

py::tuple contour(const py::object& volume, const std::vector<double>& isovalues, const py::object& spacing,
                  const py::object& origin, const std::string& normals, const std::string& weld, bool coarsen,
                  bool curvature, int threads, const py::object& callback, bool scalars, const std::string& backend,
                  bool history) {
  check_threads(threads);
  const PythonProgress progress(callback);
  generate::ContourOptions opt = contour_options(isovalues, normals, weld, coarsen, curvature, scalars, backend);
  opt.history = history;
  ArrayVolume view;  // keeps a numpy array's samples alive while the GIL is released
  const ImageGrid& grid = contour_grid(volume, spacing, origin, view);
  // A C-order array is contoured with its axes reversed: the mirrored table
  // gives the triangles of the array's own frame (those of an F-order copy).
  opt.reversed_axes = view.reversed;
  // Positions and triangles (and the scalar) only: written into the
  // module's own arrays, handed to numpy as they are.
  OwnArrays own;
  const bool own_arrays = opt.weld == generate::ContourWeld::KeyReduce &&
                          opt.normals == generate::ContourNormals::None && !coarsen && !curvature && !history &&
                          opt.backend == generate::Backend::Cpu;
  if (own_arrays)
    opt.output_arrays = [&own, &opt](Id n, Id m) { return own.allocate(n, m, opt.scalars); };
  SurfaceMesh mesh;
  std::vector<std::uint64_t> history_key;
  generate::ContourStats stats;
  double contour_s = 0, mirror_s = 0;
  run_released(threads, progress, [&] {
    progress::report("contour", 0.0);
    auto t0 = Clock::now();
    try {
      mesh = backend::contour(grid, opt, &stats, history && !coarsen ? &history_key : nullptr);
    } catch (const std::exception&) {
      rethrow_in_python_words();
    }
    contour_s = seconds_since(t0);
    t0 = Clock::now();
    if (view.reversed && own_arrays) {
      swap_x_z(own.xyz.data(), own.points);
      swap_corners(own.connectivity.data(), own.triangles);
    } else if (view.reversed) {
      mirror_axes(mesh);
      if (history) keys_in_array_frame(history_key, {grid.dims[0], grid.dims[1], grid.dims[2]});
    }
    mirror_s = seconds_since(t0);
    progress::report("contour", 1.0);
  });
  py::dict info = contour_info(stats, contour_s, mirror_s);
  info["backend"] = backend;
  py::tuple parts = own_arrays ? own.to_python(grid.name) : mesh_to_python(std::move(mesh));
  if (history) {
    const auto n = static_cast<py::ssize_t>(history_key.size());
    parts[3].cast<py::dict>()["history_key"] = adopt(std::move(history_key), {n});
  }
  return py::make_tuple(parts, info);
}

}  // namespace

// history_key in the array's own frame: a C-order array was contoured with
// its axes reversed (grid point i + nx (j + ny k) of the library's dims
// (nx, ny, nz) is array index (k, j, i), grid axis a its axis 2 - a), and the
// key the user gets is the one keymesh contour gives the same samples as a
// volume file: 3 * (x + nx' (y + ny' z)) + axis + isovalue index * 3N, x
// fastest in the array's own axes.
void keys_in_array_frame(std::vector<std::uint64_t>& keys, const std::array<Id, 3>& library_dims) {
  const auto gx = static_cast<std::uint64_t>(library_dims[0]), gy = static_cast<std::uint64_t>(library_dims[1]);
  const auto gz = static_cast<std::uint64_t>(library_dims[2]);
  const std::uint64_t per_iso = 3 * gx * gy * gz;
  parallel::for_each(static_cast<Id>(keys.size()), [&](Id p) {
    const std::uint64_t key = keys[p], iso = key / per_iso, edge = key % per_iso;
    const std::uint64_t point = edge / 3, axis = edge % 3;
    const std::uint64_t i = point % gx, j = point / gx % gy, k = point / (gx * gy);
    keys[p] = iso * per_iso + 3 * (k + gz * (j + gy * i)) + (2 - axis);
  });
}

generate::ContourOptions contour_options(const std::vector<double>& isovalues, const std::string& normals,
                                         const std::string& weld, bool coarsen, bool curvature, bool scalars,
                                         const std::string& backend) {
  if (isovalues.empty()) throw py::value_error("iso: give at least one isovalue");
  for (double v : isovalues)
    if (!std::isfinite(v)) throw py::value_error("iso must be finite, got " + std::string(py::repr(py::float_(v))));
  generate::ContourOptions opt;
  opt.isovalues = isovalues;
  opt.backend = generate::parse_option<generate::Backend>(backend);
  opt.normals = generate::parse_option<generate::ContourNormals>(normals);
  opt.weld = generate::parse_option<generate::ContourWeld>(weld);
  opt.coarsen = coarsen;
  opt.curvature = curvature;
  opt.scalars = scalars;
  return opt;
}

void mirror_axes(SurfaceMesh& mesh) {
  swap_x_z(mesh.points.data(), mesh.num_points());
  for (Field& f : mesh.point_fields)
    if (f.components == 3) swap_x_z(f.values.data(), mesh.num_points());
  swap_corners(mesh.connectivity.data(), mesh.num_cells());
}

void register_contour(py::module_& m) {
  m.def("contour", &contour, py::arg("volume"), py::arg("isovalues"), py::arg("spacing") = py::none(),
        py::arg("origin") = py::none(), py::arg("normals") = "average", py::arg("weld") = "keyreduce",
        py::arg("coarsen") = false, py::arg("curvature") = false, py::arg("threads") = 0,
        py::arg("progress") = py::none(), py::arg("scalars") = true, py::arg("backend") = "cpu",
        py::arg("history") = false,
        "Marching cubes welded by KEY-REDUCE; returns ((points, cells, offsets, point_data), timings). "
        "Use keymesh.contour, which wraps this in a Mesh.");
}

}  // namespace keymesh::python
