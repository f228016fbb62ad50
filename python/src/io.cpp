// keymesh.read / keymesh.write: the library's volume and surface mesh files.
#include "common.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/grid_io.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::python {

namespace {

// Surface meshes and grids by the format table (io/formats.hpp): a surface
// format, read or not (io::read_mesh refuses a write-only one, .glb, as the
// command does: "... .glb to write"); grids by io::is_grid_file (a .vtk may
// hold another dataset type). Everything else (a folder included) is left to
// io::read_volume, which names what the table accepts when it does not
// know the file.
bool is_mesh_path(const std::string& path) {
  const io::Format* format = io::format_by_name(path);
  return format && format->kind == io::DataKind::Surface;
}

// Returns ("volume", Volume), ("grid", grid parts) or ("mesh", (points,
// cells, offsets, point_data, cell_data)).
py::tuple read(const std::string& path, const py::object& dims, const py::object& dtype, const py::object& spacing,
               const py::object& origin, const std::string& endian, Id header_bytes) {
  refuse_nul_path(path, "read");
  if (io::is_grid_file(path)) {
    UnstructuredGrid grid;
    {
      py::gil_scoped_release release;
      grid = io::read_grid(path);
    }
    return py::make_tuple("grid", grid_to_python(std::move(grid)));
  }
  if (is_mesh_path(path) && dims.is_none() && dtype.is_none()) {
    SurfaceMesh mesh;
    {
      py::gil_scoped_release release;
      mesh = io::read_mesh(path);
    }
    return py::make_tuple("mesh", mesh_to_python(std::move(mesh)));
  }
  io::RawOptions raw;
  const bool is_raw = !dims.is_none() || !dtype.is_none();
  if (is_raw) {
    if (dims.is_none() || dtype.is_none())
      throw py::value_error(path + ": a .raw volume needs dims=(nx, ny, nz) and dtype");
    const auto d = integer_sequence(dims, "dims");
    if (d.size() != 3) throw py::value_error("dims must have 3 entries (nx, ny, nz)");
    raw.dims = {d[0], d[1], d[2]};
    raw.type = label_scalar_type_of(py::dtype::from_args(dtype), "dtype");
    if (!spacing.is_none()) raw.spacing = triple(spacing, "spacing");
    if (!origin.is_none()) raw.origin = triple(origin, "origin");
    if (endian != "little" && endian != "big") throw py::value_error("endian must be 'little' or 'big'");
    raw.big_endian = endian == "big";
    raw.header_bytes = header_bytes;
  }
  auto volume = std::make_shared<Volume>();
  {
    py::gil_scoped_release release;
    volume->grid = io::read_volume(path, is_raw ? &raw : nullptr);
  }
  return py::make_tuple("volume", volume);
}

// read() with the command's words for a file too large for this machine.
py::tuple read_or_name_memory(const std::string& path, const py::object& dims, const py::object& dtype,
                              const py::object& spacing, const py::object& origin, const std::string& endian,
                              Id header_bytes) {
  try {
    return read(path, dims, dtype, spacing, origin, endian, header_bytes);
  } catch (const std::bad_alloc&) {
    throw OutOfMemory(path + ": out of memory");
  }
}

// A Mesh's 1-D uint64 point arrays (a contour's history_key, docs/HISTORY.md),
// written as UInt64 arrays of a .vtp, their float copies taken out of the
// mesh; any other format would round them to float32, and is refused by name.
struct WidePointArrays {
  std::vector<std::string> names;
  std::vector<std::vector<std::uint64_t>> values;

  WidePointArrays(const py::handle& mesh_obj, const std::string& path, SurfaceMesh& mesh) {
    const py::object data = py::getattr(mesh_obj, "point_data", py::none());
    if (data.is_none()) return;
    for (auto item : data.cast<py::dict>()) {
      const auto a = py::array::ensure(item.second);
      if (!a || a.ndim() != 1 || !a.dtype().is(py::dtype::of<std::uint64_t>())) continue;
      const std::string name = py::str(item.first);
      if (io::file_extension(path) != ".vtp")
        throw py::value_error("write: point_data['" + name + "'] is uint64, which only .vtp holds (" + path +
                              " would round it to float32)");
      const auto v = a.cast<py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>>();
      names.push_back(name);
      values.emplace_back(v.data(), v.data() + v.size());
      std::erase_if(mesh.point_fields, [&](const Field& f) { return f.name == name; });
    }
  }
  std::vector<io::UInt64PointArray> arrays() const {
    std::vector<io::UInt64PointArray> out;
    for (std::size_t i = 0; i < names.size(); ++i) out.push_back({names[i], &values[i]});
    return out;
  }
};

void write_mesh(const py::handle& mesh_obj, const std::string& path) {
  refuse_nul_path(path, "write");
  SurfaceMesh mesh = mesh_from_python(mesh_obj);
  const WidePointArrays wide(mesh_obj, path, mesh);
  py::gil_scoped_release release;
  if (wide.names.empty()) io::write_mesh(mesh, path);
  else io::write_vtp(mesh, path, nullptr, nullptr, wide.arrays());
}

void write_grid(const py::handle& grid_obj, const std::string& path) {
  refuse_nul_path(path, "write");
  const UnstructuredGrid grid = grid_from_python(grid_obj);
  py::gil_scoped_release release;
  io::write_grid(grid, path);
}

void write_volume(const Volume& volume, const std::string& path) {
  refuse_nul_path(path, "write");
  check_volume_geometry(volume.grid, path.c_str());
  py::gil_scoped_release release;
  io::write_volume(volume.grid, path);
}

}  // namespace

void register_io(py::module_& m) {
  m.def("read", &read_or_name_memory, py::arg("path"), py::arg("dims") = py::none(), py::arg("dtype") = py::none(),
        py::arg("spacing") = py::none(), py::arg("origin") = py::none(), py::arg("endian") = "little",
        py::arg("header_bytes") = 0, "Reads a volume or a surface mesh file. Use keymesh.read.");
  // Docstrings from the format table; static: pybind11 keeps the pointer.
  using io::DataKind;
  static const std::string write_mesh_doc = "Writes a Mesh (" + io::extensions_of(DataKind::Surface, true) + ").";
  static const std::string write_grid_doc = "Writes a Grid (" + io::extensions_of(DataKind::Grid, true) + ").";
  static const std::string write_volume_doc = "Writes a Volume (" + io::extensions_of(DataKind::Volume, true) + ").";
  m.def("write_mesh", &write_mesh, py::arg("mesh"), py::arg("path"), write_mesh_doc.c_str());
  m.def("write_grid", &write_grid, py::arg("grid"), py::arg("path"), write_grid_doc.c_str());
  m.def("write_volume", &write_volume, py::arg("volume"), py::arg("path"), write_volume_doc.c_str());
}

}  // namespace keymesh::python
