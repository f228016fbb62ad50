// SurfaceMesh <-> the arrays of a Python keymesh.Mesh.
#include <cstdint>
#include <limits>

#include "common.hpp"

namespace keymesh::python {

namespace {

// An integer array as int64 (C order); TypeError for other kinds,
// MemoryError when its copy cannot be allocated.
py::array_t<std::int64_t, py::array::c_style> integers(const py::handle& obj, const char* what) {
  py::array a = py::array::ensure(obj);
  if (!a) throw py::type_error(std::string(what) + " must be an integer array");
  if (a.size() > 0 && a.dtype().kind() != 'i' && a.dtype().kind() != 'u')
    throw py::type_error(std::string(what) + " must hold integers, got dtype " + dtype_name(a.dtype()));
  auto ids = checked_array<std::int64_t>(a, what);
  if (!ids) throw py::type_error(std::string(what) + " must be an integer array");
  return ids;
}

}  // namespace

py::tuple mesh_to_python(SurfaceMesh&& mesh) {
  const py::ssize_t n = mesh.num_points();
  const py::ssize_t m = mesh.num_cells();
  py::dict point_data = fields_to_python(mesh.point_fields, n);
  py::dict cell_data = fields_to_python(mesh.cell_fields, m);
  py::array points = adopt(std::move(mesh.points), {n, 3});
  if (mesh.all_triangles())
    return py::make_tuple(points, adopt(std::move(mesh.connectivity), {m, 3}), py::none(), point_data, cell_data);
  const auto corners = static_cast<py::ssize_t>(mesh.connectivity.size());
  return py::make_tuple(points, adopt(std::move(mesh.connectivity), {corners}),
                        adopt(std::move(mesh.offsets), {m + 1}), point_data, cell_data);
}

SurfaceMesh mesh_from_python(const py::handle& obj) {
  SurfaceMesh mesh;
  auto points = checked_array<float>(obj.attr("points"), "mesh.points");
  if (!points || points.ndim() != 2 || points.shape(1) != 3)
    throw py::value_error("mesh.points must be an (n, 3) array of numbers, got shape " +
                          (points ? shape_text(points) : std::string("?")));
  const py::ssize_t n = points.shape(0);
  allocating("mesh.points", 12.0L * n, [&] { mesh.points.assign(points.data(), points.data() + 3 * n); });

  auto cells = integers(obj.attr("cells"), "mesh.cells");
  const py::object offsets_obj = py::getattr(obj, "offsets", py::none());
  const std::int64_t* ids = cells.data();
  const auto corners = static_cast<std::size_t>(cells.size());
  if (offsets_obj.is_none()) {
    if (cells.ndim() != 2 || (cells.shape(1) < 3 && cells.size() > 0))
      throw py::value_error("mesh.cells must be an (m, k) array with k >= 3 (or flat with mesh.offsets), got shape " +
                            shape_text(cells));
    const py::ssize_t m = cells.shape(0), k = cells.shape(1);
    if (k != 3)
      for (py::ssize_t c = 0; c <= m; ++c) mesh.offsets.push_back(static_cast<std::uint64_t>(c * k));
  } else {
    auto offsets = integers(offsets_obj, "mesh.offsets");
    if (offsets.ndim() != 1 || offsets.size() < 1 || offsets.data()[0] != 0 ||
        offsets.data()[offsets.size() - 1] != static_cast<std::int64_t>(corners))
      throw py::value_error("mesh.offsets must be 1-D, start at 0 and end at len(mesh.cells) = " +
                            std::to_string(corners));
    allocating("mesh.offsets", 8.0L * offsets.size(), [&] { mesh.offsets.reserve(offsets.size()); });
    for (py::ssize_t c = 0; c < offsets.size(); ++c) {
      if (c > 0 && offsets.data()[c] < offsets.data()[c - 1])
        throw py::value_error("mesh.offsets must not decrease (index " + std::to_string(c) + ")");
      mesh.offsets.push_back(static_cast<std::uint64_t>(offsets.data()[c]));
    }
  }
  allocating("mesh.cells", 4.0L * corners, [&] { mesh.connectivity.resize(corners); });
  for (std::size_t i = 0; i < corners; ++i) {
    if (ids[i] < 0 || ids[i] >= n)
      throw py::value_error("mesh.cells refers to point " + std::to_string(ids[i]) + " but the mesh has " +
                            std::to_string(n) + " points");
    mesh.connectivity[i] = static_cast<PointIndex>(ids[i]);
  }

  mesh.point_fields = fields_from_python(py::getattr(obj, "point_data", py::none()), n, "mesh.point_data");
  mesh.cell_fields = fields_from_python(py::getattr(obj, "cell_data", py::none()), mesh.num_cells(), "mesh.cell_data");
  return mesh;
}

}  // namespace keymesh::python
