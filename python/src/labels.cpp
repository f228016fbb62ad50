// keymesh.contour_labels: surfaces of a label map (generate/labels.hpp) over a
// numpy integer volume or a keymesh.Volume. Axis 0 is x, as in contour; the
// library reads the samples x-fastest, so a C-ordered array is copied once
// into Fortran order (labels are small integers: the copy is cheap next to
// the generator).
#include "common.hpp"
#include "keymesh/generate/labels/labels.hpp"
#include "keymesh/generate/option_names.hpp"
#include "keymesh/generate/report_fields.hpp"

namespace keymesh::python {

namespace {

// Python's names, or the command's (generate/option_names.hpp).
generate::LabelMethod parse_method(const std::string& s) {
  if (s == "surface_nets") return generate::LabelMethod::SurfaceNets;
  if (s == "discrete_marching_cubes") return generate::LabelMethod::DiscreteMarchingCubes;
  if (const auto method = generate::find_option<generate::LabelMethod>(s)) return *method;
  throw py::value_error("method must be 'surface_nets' or 'discrete_marching_cubes', got '" + s + "'");
}

py::tuple contour_labels(const py::object& volume, const py::object& spacing, const py::object& origin,
                         const std::string& method, const std::vector<std::int64_t>& labels,
                         std::int64_t background, bool per_label, int smoothing_iterations, double relaxation,
                         bool coarsen, int threads, bool history) {
  check_threads(threads);
  generate::LabelOptions opt =
      label_options(method, labels, background, per_label, smoothing_iterations, relaxation, coarsen);
  opt.history = history;
  ArrayVolume view;
  const ImageGrid& grid = label_grid(volume, spacing, origin, view, "contour_labels");
  generate::LabelStats stats;
  std::vector<std::uint64_t> history_key;
  SurfaceMesh mesh = run_released(threads, [&] {
    return generate::contour_labels(grid, opt, &stats, history ? &history_key : nullptr);
  });
  py::dict info;
  generate::visit_stage_seconds(stats, into(info));
  info["distinct_labels"] = stats.distinct_labels;
  info["surfaces"] = stats.surfaces;
  info["guard_shortened"] = stats.guard_shortened;
  return py::make_tuple(with_history_key(mesh_to_python(std::move(mesh)), std::move(history_key), history), info);
}

}  // namespace

// The labels' history_key (the padded grid's, in the array's frame: the
// volume is read in Fortran order, axis 0 = x) as point_data["history_key"].
py::tuple with_history_key(py::tuple parts, std::vector<std::uint64_t>&& history_key, bool history) {
  if (!history) return parts;
  const auto n = static_cast<py::ssize_t>(history_key.size());
  parts[3].cast<py::dict>()["history_key"] = adopt(std::move(history_key), {n});
  return parts;
}

const ImageGrid& label_grid(const py::object& volume, const py::object& spacing, const py::object& origin,
                            ArrayVolume& view, const char* command) {
  if (!py::isinstance<Volume>(volume)) {
    view = view_array_volume(volume, spacing, origin, VolumeOrder::Fortran,
                             {command, 1, "volume must be a 3-D numpy array or a keymesh.Volume", true});
    return view.grid;
  }
  const ImageGrid& grid = volume.cast<Volume&>().grid;
  check_volume_geometry(grid, command);
  return grid;
}

generate::LabelOptions label_options(const std::string& method, const std::vector<std::int64_t>& labels,
                                     std::int64_t background, bool per_label, int smoothing_iterations,
                                     double relaxation, bool coarsen) {
  generate::LabelOptions opt;
  opt.method = parse_method(method);
  opt.labels = labels;
  opt.background = background;
  opt.per_label = per_label;
  opt.smooth_iterations = smoothing_iterations;
  opt.relaxation = relaxation;
  opt.coarsen = coarsen;
  return opt;
}

void register_labels(py::module_& m) {
  m.def("contour_labels", &contour_labels, py::arg("volume"), py::arg("spacing") = py::none(),
        py::arg("origin") = py::none(), py::arg("method") = "surface_nets",
        py::arg("labels") = std::vector<std::int64_t>{}, py::arg("background") = 0, py::arg("per_label") = false,
        py::arg("smoothing_iterations") = 16, py::arg("relaxation") = 0.5, py::arg("coarsen") = false, py::arg("threads") = 0,
        py::arg("history") = false,
        "Surfaces of a label map; returns ((points, cells, offsets, point_data, cell_data), info). "
        "Use keymesh.contour_labels, which wraps this in a Mesh.");
}

}  // namespace keymesh::python
