// UnstructuredGrid <-> the arrays of a Python keymesh.Grid.
#include <cstdint>
#include <string>

#include "common.hpp"

namespace keymesh::python {

py::dict fields_to_python(std::vector<Field>& fields, py::ssize_t rows) {
  py::dict out;
  for (Field& f : fields) {
    std::vector<py::ssize_t> shape{rows};
    if (f.components != 1) shape.push_back(f.components);
    out[py::str(f.name)] = adopt(std::move(f.values), std::move(shape));
  }
  return out;
}

std::vector<Field> fields_from_python(const py::object& data, py::ssize_t rows, const char* what) {
  std::vector<Field> out;
  if (data.is_none()) return out;
  for (auto item : data.cast<py::dict>()) {
    const std::string name = py::str(item.first);
    const std::string label = std::string(what) + "['" + name + "']";
    auto values = checked_array<float>(item.second, label.c_str());
    if (!values || values.ndim() < 1 || values.ndim() > 2 || values.shape(0) != rows)
      throw py::value_error(label + " must have " + std::to_string(rows) + " rows, 1 or 2 dimensions");
    Field f;
    f.name = name;
    f.components = values.ndim() == 2 ? static_cast<int>(values.shape(1)) : 1;
    allocating(label.c_str(), 4.0L * values.size(),
               [&] { f.values.assign(values.data(), values.data() + values.size()); });
    out.push_back(std::move(f));
  }
  return out;
}

py::tuple grid_to_python(UnstructuredGrid&& grid) {
  const py::ssize_t n = grid.num_points();
  const py::ssize_t m = grid.num_cells();
  py::dict point_data = fields_to_python(grid.point_fields, n);
  py::dict cell_data = fields_to_python(grid.cell_fields, m);
  py::array points = adopt(std::move(grid.points), {n, 3});
  const auto corners = static_cast<py::ssize_t>(grid.connectivity.size());
  std::vector<py::ssize_t> shape{corners};
  if (grid.uniform()) shape = {m, static_cast<py::ssize_t>(cell_type_size(grid.uniform_type))};
  py::array cells = grid.connectivity.wide() ? adopt(std::move(grid.connectivity.wide_values()), shape)
                                             : adopt(std::move(grid.connectivity.narrow()), shape);
  py::object offsets = py::none(), types = py::none();
  if (!grid.uniform()) {
    offsets = adopt(std::move(grid.offsets), {m + 1});
    if (grid.cell_types.empty()) grid.cell_types.assign(static_cast<std::size_t>(m), static_cast<std::uint8_t>(grid.uniform_type));
    types = adopt(std::move(grid.cell_types), {m});
  }
  return py::make_tuple(points, cells, offsets, types, static_cast<int>(grid.uniform_type), point_data, cell_data);
}

namespace {

// A VTK cell type code (a byte); ValueError naming grid.cell_type otherwise
// (pybind11's own cast says only that an int could not be cast).
int cell_type_code(const py::handle& value) {
  const auto code = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
  if (!code) throw py::error_already_set();  // TypeError: not an integer
  int overflow = 0;
  const long long c = PyLong_AsLongLongAndOverflow(code.ptr(), &overflow);
  if (overflow != 0 || c < 0 || c > 255)
    throw py::value_error("grid.cell_type must be a VTK cell type code (0..255), got " +
                          (overflow != 0 ? "an integer past 64 bits" : std::to_string(c)));
  return static_cast<int>(c);
}

}  // namespace

UnstructuredGrid grid_from_python(const py::handle& obj) {
  UnstructuredGrid grid;
  auto points = checked_array<float>(obj.attr("points"), "grid.points");
  if (!points || points.ndim() != 2 || points.shape(1) != 3)
    throw py::value_error("grid.points must be an (n, 3) array of numbers");
  const py::ssize_t n = points.shape(0);
  allocating("grid.points", 12.0L * n, [&] { grid.points.assign(points.data(), points.data() + 3 * n); });
  auto cells = checked_array<std::int64_t>(obj.attr("cells"), "grid.cells");
  if (!cells) throw py::type_error("grid.cells must be an integer array");
  const py::object offsets_obj = py::getattr(obj, "offsets", py::none());
  const py::object types_obj = py::getattr(obj, "cell_types", py::none());
  grid.uniform_type = static_cast<CellType>(cell_type_code(py::getattr(obj, "cell_type", py::int_(10))));
  const auto corners = static_cast<std::size_t>(cells.size());
  allocating("grid.cells", 8.0L * corners,
             [&] { grid.connectivity = IndexArray::for_ids(static_cast<std::uint64_t>(n), corners); });
  for (std::size_t i = 0; i < corners; ++i) grid.connectivity.set(i, static_cast<std::uint64_t>(cells.data()[i]));
  if (!offsets_obj.is_none()) {
    auto offsets = checked_array<std::int64_t>(offsets_obj, "grid.offsets");
    if (!offsets || offsets.ndim() != 1) throw py::value_error("grid.offsets must be a 1-D integer array");
    allocating("grid.offsets", 8.0L * offsets.size(), [&] { grid.offsets.reserve(offsets.size()); });
    for (py::ssize_t c = 0; c < offsets.size(); ++c) {
      if (offsets.data()[c] < 0) throw py::value_error("grid.offsets must not be negative");
      grid.offsets.push_back(static_cast<std::uint64_t>(offsets.data()[c]));
    }
    if (!types_obj.is_none()) {
      auto types = checked_array<std::uint8_t>(types_obj, "grid.cell_types");
      if (!types || types.ndim() != 1) throw py::value_error("grid.cell_types must be a 1-D array");
      allocating("grid.cell_types", types.size(),
                 [&] { grid.cell_types.assign(types.data(), types.data() + types.size()); });
    }
  } else if (cells.ndim() != 2 || cells.shape(1) != cell_type_size(grid.uniform_type)) {
    throw py::value_error("grid.cells must be (m, " + std::to_string(cell_type_size(grid.uniform_type)) +
                          ") for cells of type " + cell_type_name(static_cast<std::uint8_t>(grid.uniform_type)) +
                          ", or flat with grid.offsets");
  }
  grid.point_fields = fields_from_python(py::getattr(obj, "point_data", py::none()), n, "grid.point_data");
  grid.cell_fields = fields_from_python(py::getattr(obj, "cell_data", py::none()), grid.num_cells(), "grid.cell_data");
  grid.validate("grid");
  return grid;
}

}  // namespace keymesh::python
