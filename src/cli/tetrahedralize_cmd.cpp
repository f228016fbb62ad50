// keymesh tetrahedralize IN -o OUT.vtu --scheme 5|24: hexahedra (voxels of a
// volume, or hexahedral cells of a .vtu/.vtk) split into tetrahedra.
#include <algorithm>
#include <cstdio>

#include "command.hpp"
#include "keymesh/backend/tetrahedralize.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/grid_io.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

namespace {

struct TetrahedralizeCli {
  std::string input, output;
  int scheme = 5;
  std::string weld = "keyreduce";
  CommonOptions common;
};

void add_tetrahedralize_options(Subcommand& cmd, TetrahedralizeCli& o) {
  cmd.description("split the voxels of a volume (or the hexahedra of a " +
                  io::extensions_of(io::DataKind::Grid, false, "/") + ") into tetrahedra");
  cmd.add_option("input", o.input,
                 "volume (" + volume_inputs() + ") or hexahedral grid (" +
                     io::extensions_of(io::DataKind::Grid, false) + ")")
      ->required();
  cmd.add_option("-o,--output", o.output, "output tetrahedral grid (" + io::extensions_of(io::DataKind::Grid, true) + ")")
      ->required();
  cmd.add_option("--scheme", o.scheme,
                 "5: five tets per hexahedron, alternating so neighbouring faces match (the minimal split); "
                 "24: face-centred, 24 tets per hexahedron from its centre and its face centres")
      ->check(member_of({5, 24}));
  cmd.add_option("--weld", o.weld,
                 "scheme 24: face centres shared by KEY-REDUCE on face keys (keyreduce) or by coordinates "
                 "(vertexweld, the baseline)")
      ->check(one_of<generate::SubdivideWeld>());
  add_common_options(cmd, o.common);
}

int run_tetrahedralize(const TetrahedralizeCli& o, CommandRun& run) {
  Progress progress(o.common.quiet, file_size(o.input) > (64ll << 20));
  progress.say("reading " + o.input);
  const bool vertexweld =
      generate::parse_option<generate::SubdivideWeld>(o.weld) == generate::SubdivideWeld::VertexWeld;
  const auto backend = generate::parse_option<generate::Backend>(o.common.backend);
  UnstructuredGrid tets;
  nlohmann::json r;
  if (io::is_grid_file(o.input)) {
    const UnstructuredGrid hexes = run.stage("read", [&] { return io::read_grid(o.input); });
    check_work(estimate_tetrahedralize(hexes.num_points(), hexes.num_cells(), o.scheme,
                                       field_components(hexes.point_fields)),
               memory_budget(o.common), o.input + ": tetrahedralize --scheme " + std::to_string(o.scheme));
    tets = run.stage("tetrahedralize",
                     [&] { return backend::tetrahedralize(hexes, o.scheme, vertexweld, backend); });
    r["input_cells"] = hexes.num_cells();
  } else {
    const ImageGrid grid = run.stage("read", [&] { return io::read_volume(o.input); });
    const auto voxels = [&] {
      std::uint64_t n = 1;
      for (Id d : grid.dims) n = saturating_mul(n, static_cast<std::uint64_t>(std::max<Id>(d - 1, 0)));
      return n;
    }();
    check_work(estimate_tetrahedralize(static_cast<std::uint64_t>(grid.num_points()), voxels, o.scheme, 1),
               memory_budget(o.common), o.input + ": tetrahedralize --scheme " + std::to_string(o.scheme));
    progress.enable_if(grid.num_points() > (1ll << 24));
    progress.say("tetrahedralizing " + std::to_string(grid.dims[0]) + "x" + std::to_string(grid.dims[1]) + "x" +
                 std::to_string(grid.dims[2]));
    tets = run.stage("tetrahedralize",
                     [&] { return backend::tetrahedralize(grid, o.scheme, vertexweld, backend); });
    r["dims"] = grid.dims;
  }
  progress.say("writing " + o.output);
  run.stage("write", [&] { io::write_grid(tets, o.output); });
  say_written(o.common, tets.num_points(), tets.num_cells(), "tetrahedra", o.output);
  r.update(files_and_counts(o.input, o.output, tets.num_points(), tets.num_cells()));
  r["scheme"] = o.scheme;
  r["weld"] = o.weld;
  r["backend"] = o.common.backend;
  return run.finish(r, PeakRss::Include);
}

Register reg{make_run_command("tetrahedralize", add_tetrahedralize_options, run_tetrahedralize)};

}  // namespace

}  // namespace keymesh::cli
