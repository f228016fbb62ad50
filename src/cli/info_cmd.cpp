// keymesh info FILE: what a volume or mesh file holds.
#include <array>
#include <cstdint>
#include <cstdio>
#include <map>

#include "command.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/grid_io.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

namespace {

struct InfoCli {
  std::string input;
  std::string report_path;
};

void add_info_options(Subcommand& cmd, InfoCli& o) {
  cmd.add_option("file", o.input,
                 "volume (" + volume_inputs() + "), surface mesh (" +
                     io::extensions_of(io::DataKind::Surface, false) + ") or unstructured grid (" +
                     io::extensions_of(io::DataKind::Grid, false) + ")")
      ->required();
  cmd.add_option("--report", o.report_path, "write the same facts as JSON");
}

// Prints a grid's or surface's point and cell fields; their report entries.
nlohmann::json list_fields(const std::vector<Field>& point_fields, const std::vector<Field>& cell_fields) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto* fields : {&point_fields, &cell_fields})
    for (const auto& f : *fields) {
      const char* where = fields == &point_fields ? "point" : "cell";
      std::printf("  %s field %s (%d component%s)\n", where, f.name.c_str(), f.components, f.components == 1 ? "" : "s");
      out.push_back({{"name", f.name}, {"components", f.components}, {"association", where}});
    }
  return out;
}

int run_info(const InfoCli& o) {
  nlohmann::json r;
  r["file"] = o.input;
  // A grid format (.vtu, .vtk) is read as a grid, without is_grid_file's
  // look at a legacy header: for a .vtk holding POLYDATA, or no VTK header,
  // the grid reader says what the file holds instead of "unknown volume
  // format".
  const io::Format* format = io::input_format(o.input);
  if (format && format->kind == io::DataKind::Grid) {
    const UnstructuredGrid g = io::read_grid(o.input);
    // Counted by type code first: 82.9 M cells are too many for a map keyed by name.
    std::array<Id, 256> by_code{};
    if (g.cell_types.empty()) by_code[static_cast<std::uint8_t>(g.uniform_type)] = g.num_cells();
    for (const std::uint8_t t : g.cell_types) ++by_code[t];
    std::map<std::string, Id> by_type;
    for (int t = 0; t < 256; ++t)
      if (by_code[t] > 0) by_type[cell_type_name(static_cast<std::uint8_t>(t))] = by_code[t];
    std::printf("%s: unstructured grid\n  points %lld\n  cells %lld\n", o.input.c_str(),
                (long long)g.num_points(), (long long)g.num_cells());
    r["kind"] = "grid";
    r["points"] = g.num_points();
    r["cells"] = g.num_cells();
    r["cell_types"] = nlohmann::json::object();
    for (const auto& [name, n] : by_type) {
      std::printf("    %s %lld\n", name.c_str(), (long long)n);
      r["cell_types"][name] = n;
    }
    r["fields"] = list_fields(g.point_fields, g.cell_fields);
  } else if (is_mesh_path(o.input)) {
    const SurfaceMesh mesh = io::read_mesh(o.input);
    std::printf("%s: surface mesh\n  points %lld\n  cells %lld (%s)\n", o.input.c_str(),
                (long long)mesh.num_points(), (long long)mesh.num_cells(),
                mesh.all_triangles() ? "triangles" : "polygons");
    r["kind"] = "mesh";
    r["points"] = mesh.num_points();
    r["cells"] = mesh.num_cells();
    r["fields"] = list_fields(mesh.point_fields, mesh.cell_fields);
  } else {
    const ImageGrid grid = io::read_volume(o.input);
    const auto range = scalar_range(grid);
    std::printf("%s: volume\n  dims %lld x %lld x %lld\n  type %s\n  range %g .. %g\n  spacing %g %g %g\n"
                "  origin %g %g %g\n  field %s\n",
                o.input.c_str(), (long long)grid.dims[0], (long long)grid.dims[1], (long long)grid.dims[2],
                scalar_type_name(grid.type), range[0], range[1], grid.spacing[0], grid.spacing[1],
                grid.spacing[2], grid.origin[0], grid.origin[1], grid.origin[2], grid.name.c_str());
    r["kind"] = "volume";
    r["dims"] = grid.dims;
    r["type"] = scalar_type_name(grid.type);
    r["range"] = range;
    r["spacing"] = grid.spacing;
    r["origin"] = grid.origin;
    r["points"] = grid.num_points();
  }
  if (!o.report_path.empty()) write_report(o.report_path, r);
  return 0;
}

Register reg{make_command<InfoCli>(
    "info", "dims, type, range and spacing of a volume; points, cells and fields of a mesh",
    add_info_options, run_info)};

}  // namespace

}  // namespace keymesh::cli
