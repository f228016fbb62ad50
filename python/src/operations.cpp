// The CLI's operations as functions over Mesh / Grid / volume arrays:
// tetrahedralize, subdivide, dual, quality, coarsen, incidence. Each copies
// its input into the library's types with the GIL held, runs with the GIL
// released under the progress hook (Ctrl-C, progress=), and hands the
// library's output buffers to numpy without a copy.
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "common.hpp"
#include "keymesh/analyze/incidence.hpp"
#include "keymesh/analyze/report_fields.hpp"
#include "keymesh/generate/coarsen/coarsen.hpp"
#include "keymesh/generate/unstructured/dual.hpp"
#include "keymesh/generate/option_names.hpp"
#include "keymesh/generate/report_fields.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "keymesh/mesh/normals.hpp"

namespace keymesh::python {

namespace {

// A numpy volume as the library's x-fastest grid: a Fortran-ordered array
// (axis 0 fastest) is read in place, anything else is copied into that
// order once. `keep` holds the array the grid views.
ImageGrid volume_grid(const py::object& volume, const py::object& spacing, const py::object& origin, py::object& keep) {
  if (py::isinstance<Volume>(volume)) {  // viewed in place, like contour does
    const ImageGrid& src = volume.cast<Volume&>().grid;
    check_volume_geometry(src, "tetrahedralize");
    ImageGrid g;
    g.dims = src.dims;
    g.spacing = src.spacing;
    g.origin = src.origin;
    g.type = src.type;
    g.name = src.name;
    g.external = static_cast<const std::byte*>(src.data());
    keep = volume;
    return g;
  }
  ArrayVolume view = view_array_volume(
      volume, spacing, origin, VolumeOrder::Fortran,
      {"tetrahedralize", 2, "volume must be a 3-D numpy array, a keymesh.Volume or a keymesh.Grid"});
  keep = view.array;
  return view.grid;
}

py::tuple tetrahedralize(const py::object& input, int scheme, const std::string& weld, const py::object& spacing,
                         const py::object& origin, int threads, const py::object& callback) {
  check_threads(threads);
  if (scheme != 5 && scheme != 24) throw py::value_error("scheme must be 5 or 24, got " + std::to_string(scheme));
  // scheme 24's face centres: by face keys or by coordinates, subdivision's two choices
  const bool vw = generate::parse_option<generate::SubdivideWeld>(weld) == generate::SubdivideWeld::VertexWeld;
  const PythonProgress progress(callback);
  const bool from_grid = py::hasattr(input, "cells") && py::hasattr(input, "points");
  UnstructuredGrid hexes;
  ImageGrid volume;
  py::object keep;
  if (from_grid) hexes = grid_from_python(input);
  else volume = volume_grid(input, spacing, origin, keep);
  UnstructuredGrid tets = run_released_stage(threads, progress, "tetrahedralize", [&] {
    if (from_grid) return scheme == 24 ? generate::tetrahedralize24(hexes, vw) : generate::tetrahedralize5(hexes);
    return scheme == 24 ? generate::tetrahedralize24(volume, vw) : generate::tetrahedralize5(volume);
  });
  return grid_to_python(std::move(tets));
}

generate::SubdivideOptions subdivide_options(int levels, const std::string& scheme, const std::string& weld) {
  if (levels < 0 || levels > 8) throw py::value_error("levels must be in [0, 8], got " + std::to_string(levels));
  generate::SubdivideOptions opt;
  opt.scheme = generate::parse_option<generate::SubdivideScheme>(scheme);
  opt.weld = generate::parse_option<generate::SubdivideWeld>(weld);
  opt.levels = levels;
  return opt;
}

// A surface (1 -> 4) or tet grid (1 -> 8) subdivided with the GIL released.
template <class Geometry>
Geometry subdivide_released(Geometry geometry, const generate::SubdivideOptions& opt, int threads,
                            const PythonProgress& progress) {
  return run_released(threads, progress, [&] {
    Geometry subdivided = generate::subdivide(geometry, opt);  // reports every level
    progress::report("subdivide", 1.0);
    return subdivided;
  });
}

py::tuple subdivide_mesh(const py::handle& mesh_obj, int levels, const std::string& scheme, const std::string& weld,
                         int threads, const py::object& callback) {
  check_threads(threads);
  const auto opt = subdivide_options(levels, scheme, weld);
  const PythonProgress progress(callback);
  return mesh_to_python(subdivide_released(mesh_from_python(mesh_obj), opt, threads, progress));
}

py::tuple subdivide_grid(const py::handle& grid_obj, int levels, const std::string& scheme, const std::string& weld,
                         int threads, const py::object& callback) {
  check_threads(threads);
  const auto opt = subdivide_options(levels, scheme, weld);
  if (opt.scheme == generate::SubdivideScheme::Bezier)
    throw py::value_error("scheme='bezier' is for surfaces; tets use 'linear'");
  const PythonProgress progress(callback);
  return grid_to_python(subdivide_released(grid_from_python(grid_obj), opt, threads, progress));
}

py::tuple dual(const py::handle& mesh_obj, int threads, const py::object& callback) {
  check_threads(threads);
  const PythonProgress progress(callback);
  const SurfaceMesh mesh = mesh_from_python(mesh_obj);
  generate::DualStats st;
  SurfaceMesh d = run_released_stage(threads, progress, "dual", [&] { return generate::dual(mesh, &st); });
  py::dict stats;
  generate::visit_fields(st, into(stats));
  return py::make_tuple(mesh_to_python(std::move(d)), stats);
}

py::dict quality(const py::handle& mesh_obj, bool per_cell, int threads) {
  check_threads(threads);
  const SurfaceMesh mesh = mesh_from_python(mesh_obj);
  std::vector<double> each;
  const analyze::QualityReport q = run_released(threads, [&] {
    if (per_cell) each = analyze::triangle_quality(mesh);
    return analyze::quality(mesh);
  });
  py::dict r;
  r["points"] = mesh.num_points();
  analyze::visit_fields(q, into(r));
  if (per_cell) {
    const auto n = static_cast<py::ssize_t>(each.size());
    r["per_cell"] = adopt(std::move(each), {n});
  }
  return r;
}

// Every point's key: the lattice point (origin + i * spacing) nearest to
// it, numbered x-fastest over the lattice's bounding box (range: its size).
struct LatticeKeys {
  std::vector<std::uint64_t> keys;
  std::uint64_t range = 1;
};

// Why point p has no lattice index along axis a: the point itself is not
// finite, or the spacing and origin (checked finite) put it past 9e15
// spacings from the origin (a spacing of 1e-300, an origin of 3e38).
InputError lattice_error(const SurfaceMesh& mesh, Id p, int a, const std::array<double, 3>& s,
                         const std::array<double, 3>& o) {
  const float x = mesh.points[3 * p + a];
  if (!std::isfinite(x)) return InputError("coarsen: point " + std::to_string(p) + " is not finite");
  char b[160];
  std::snprintf(b, sizeof b, "lies %.3g spacings from the origin along %c (point %g, origin %g, spacing %g)",
                (static_cast<double>(x) - o[a]) / s[a], "xyz"[a], static_cast<double>(x), o[a], s[a]);
  return InputError("coarsen: point " + std::to_string(p) + " " + b +
                    ", past the 9e15 a lattice index holds: the spacing is too fine or the origin too far for this "
                    "mesh (give the spacing and origin of the grid it was contoured on)");
}

LatticeKeys lattice_keys(const SurfaceMesh& mesh, const std::array<double, 3>& s, const std::array<double, 3>& o) {
  const Id n = mesh.num_points();
  std::array<std::int64_t, 3> lo{0, 0, 0}, hi{0, 0, 0};
  std::vector<std::int64_t> lattice(static_cast<std::size_t>(3 * n));
  for (Id p = 0; p < n; ++p)
    for (int a = 0; a < 3; ++a) {
      const double t = std::floor((mesh.points[3 * p + a] - o[a]) / s[a] + 0.5);
      if (!(std::fabs(t) < 9e15)) throw lattice_error(mesh, p, a, s, o);
      const auto i = static_cast<std::int64_t>(t);
      lattice[3 * p + a] = i;
      if (p == 0 || i < lo[a]) lo[a] = i;
      if (p == 0 || i > hi[a]) hi[a] = i;
    }
  std::array<std::uint64_t, 3> extent{};
  long double range = 1;
  for (int a = 0; a < 3; ++a) {
    extent[a] = static_cast<std::uint64_t>(hi[a] - lo[a] + 1);
    range *= static_cast<long double>(extent[a]);
  }
  if (range > static_cast<long double>(std::uint64_t(1) << 40))
    throw LimitError("coarsen: the mesh spans " + std::to_string(static_cast<double>(range)) +
                     " lattice points; give the spacing of the grid it was contoured on");
  LatticeKeys result;
  result.keys.resize(static_cast<std::size_t>(n));
  for (Id p = 0; p < n; ++p)
    result.keys[p] = static_cast<std::uint64_t>(lattice[3 * p] - lo[0]) +
                     extent[0] * (static_cast<std::uint64_t>(lattice[3 * p + 1] - lo[1]) +
                                  extent[1] * static_cast<std::uint64_t>(lattice[3 * p + 2] - lo[2]));
  result.range = n == 0 ? 1 : static_cast<std::uint64_t>(range);
  return result;
}

// Coarsening an existing mesh: every point is keyed by the lattice point
// (origin + i * spacing) nearest to it, the key of `contour --coarsen` for a
// mesh contoured on that lattice (rounding half up, like its t >= 0.5).
py::tuple coarsen(const py::handle& mesh_obj, const py::object& spacing, const py::object& origin,
                  const std::string& normals, int threads, const py::object& callback) {
  check_threads(threads);
  if (normals != "average" && normals != "merge")
    throw py::value_error("normals must be 'average' or 'merge', got '" + normals + "'");
  const std::array<double, 3> s = triple(spacing, "spacing"), o = triple(origin, "origin");
  check_float32_geometry({1, 1, 1}, o, s, "coarsen");  // finite, named (the volume readers' check)
  for (int a = 0; a < 3; ++a)
    if (!(s[a] > 0)) throw py::value_error("spacing must be positive and finite");
  const PythonProgress progress(callback);
  const SurfaceMesh mesh = mesh_from_python(mesh_obj);
  generate::CoarsenStats st;
  SurfaceMesh out = run_released(threads, progress, [&] {
    progress::report("coarsen: keys", 0.0);
    const LatticeKeys lattice = lattice_keys(mesh, s, o);
    progress::report("coarsen: merge", 0.3);
    SurfaceMesh coarse = generate::coarsen(mesh, lattice.keys, lattice.range, &st);
    if (normals == "average" && mesh.find_point_field("Normals") != nullptr) average_normals(coarse);
    progress::report("coarsen", 1.0);
    return coarse;
  });
  py::dict stats;
  generate::visit_fields(st, into(stats));
  return py::make_tuple(mesh_to_python(std::move(out)), stats);
}

// (point_offsets, point_cells, cell_neighbours): the cells of point p are
// point_cells[point_offsets[p]:point_offsets[p + 1]] (increasing corner
// order); cell_neighbours has one entry per corner of every cell (the cell
// across the edge from that corner to the next; -1 boundary, -2 non-manifold).
py::tuple incidence(const py::handle& mesh_obj, int threads) {
  check_threads(threads);
  const SurfaceMesh mesh = mesh_from_python(mesh_obj);
  analyze::PointCells pc;
  std::vector<std::int64_t> neighbours;
  std::vector<std::uint32_t> cells;
  run_released(threads, [&] {
    pc = analyze::point_cells(mesh);
    cells.resize(pc.corners.size());
    for (std::size_t i = 0; i < cells.size(); ++i) cells[i] = pc.cell_of(pc.corners[i]);
    neighbours = analyze::cell_neighbours(mesh);
  });
  const auto n_off = static_cast<py::ssize_t>(pc.offsets.size());
  const auto n_cells = static_cast<py::ssize_t>(cells.size());
  py::array nb;
  const auto n_nb = static_cast<py::ssize_t>(neighbours.size());
  if (mesh.all_triangles()) nb = adopt(std::move(neighbours), {n_nb / 3, 3});
  else nb = adopt(std::move(neighbours), {n_nb});
  return py::make_tuple(adopt(std::move(pc.offsets), {n_off}), adopt(std::move(cells), {n_cells}), nb);
}

}  // namespace

void register_operations(py::module_& m) {
  m.def("tetrahedralize", &tetrahedralize, py::arg("input"), py::arg("scheme") = 5, py::arg("weld") = "keyreduce",
        py::arg("spacing") = py::none(), py::arg("origin") = py::none(), py::arg("threads") = 0,
        py::arg("progress") = py::none(), "Use keymesh.tetrahedralize.");
  m.def("subdivide_mesh", &subdivide_mesh, py::arg("mesh"), py::arg("levels"), py::arg("scheme"), py::arg("weld"),
        py::arg("threads") = 0, py::arg("progress") = py::none(), "Use keymesh.subdivide.");
  m.def("subdivide_grid", &subdivide_grid, py::arg("grid"), py::arg("levels"), py::arg("scheme"), py::arg("weld"),
        py::arg("threads") = 0, py::arg("progress") = py::none(), "Use keymesh.subdivide.");
  m.def("dual", &dual, py::arg("mesh"), py::arg("threads") = 0, py::arg("progress") = py::none(),
        "Use keymesh.dual.");
  m.def("quality", &quality, py::arg("mesh"), py::arg("per_cell") = false, py::arg("threads") = 0,
        "Use keymesh.quality.");
  m.def("coarsen", &coarsen, py::arg("mesh"), py::arg("spacing"), py::arg("origin"), py::arg("normals") = "average",
        py::arg("threads") = 0, py::arg("progress") = py::none(), "Use keymesh.coarsen.");
  m.def("incidence", &incidence, py::arg("mesh"), py::arg("threads") = 0, "Use keymesh.incidence.");
}

}  // namespace keymesh::python
