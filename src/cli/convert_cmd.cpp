// keymesh convert IN -o OUT: one file format to another of the same kind
// (unstructured grid, surface mesh or volume), as the format table
// (io/formats.hpp) says.
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "command.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/grid_io.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

namespace {

enum class Kind { Grid, Surface, Volume, Unknown };

const char* kind_name(Kind k) {
  switch (k) {
    case Kind::Grid: return "an unstructured grid";
    case Kind::Surface: return "a surface mesh";
    case Kind::Volume: return "a volume";
    case Kind::Unknown: break;
  }
  return "an unknown format";
}

// The kind a file holds, by its name in the format table (a folder: the
// folder formats'), whether or not keymesh reads or writes that format: the
// reader or writer then names the extensions it accepts. A .vtk is always
// read as a grid: the grid reader names any other dataset type it finds.
Kind kind_of(const std::string& path, bool output) {
  const io::Format* format = output ? io::format_by_name(path) : io::input_format(path);
  if (!format) return Kind::Unknown;
  switch (format->kind) {
    case io::DataKind::Grid: return Kind::Grid;
    case io::DataKind::Surface: return Kind::Surface;
    case io::DataKind::Volume: return Kind::Volume;
  }
  return Kind::Unknown;
}

struct ConvertCli {
  std::string input, output;
  CommonOptions common;
};

void add_convert_options(Subcommand& cmd, ConvertCli& o) {
  using io::DataKind;
  cmd.add_option("input", o.input,
                 "unstructured grid (" + io::extensions_of(DataKind::Grid, false) + "), surface mesh (" +
                     io::extensions_of(DataKind::Surface, false) + ") or volume (" +
                     volume_inputs() + ")")
      ->required();
  cmd.add_option("-o,--output", o.output,
                 "output file of the same kind (volumes: " + io::extensions_of(DataKind::Volume, true) + ")")
      ->required();
  add_common_options(cmd, o.common);
}

int run_convert(const ConvertCli& o) {
  if (int rc = require_cpu_backend(o.common, "convert")) return rc;
  const int threads = apply_threads(o.common);
  const Kind in = kind_of(o.input, false), out = kind_of(o.output, true);
  if (in == Kind::Unknown) {
    // A missing input is that, whatever its name would make it.
    std::error_code missing;
    if (!std::filesystem::exists(o.input, missing)) throw InputError(o.input + ": no such file");
    std::fprintf(stderr, "keymesh: convert: %s: unknown input format\n", printable(o.input).c_str());
    return 2;
  }
  if (out == Kind::Unknown) {
    std::fprintf(stderr, "keymesh: convert: %s: unknown output format\n", printable(o.output).c_str());
    return 2;
  }
  if (in != out) {
    std::fprintf(stderr, "keymesh: convert: %s is %s and %s would be %s; convert keeps the kind of data\n",
                 printable(o.input).c_str(), kind_name(in), printable(o.output).c_str(), kind_name(out));
    return 2;
  }
  StageTimer timer;
  Progress progress(o.common.quiet, file_size(o.input) > (64ll << 20));
  progress.say("reading " + o.input);
  nlohmann::json r;
  long long points = 0, cells = 0;
  if (in == Kind::Grid) {
    const UnstructuredGrid g = timer.run("read", [&] { return io::read_grid(o.input); });
    points = g.num_points(), cells = g.num_cells();
    check_memory(o.common, bytes_held(g), o.input + ": convert: the data read");
    progress.say("writing " + o.output);
    timer.run("write", [&] { io::write_grid(g, o.output); });
  } else if (in == Kind::Surface) {
    const SurfaceMesh m = timer.run("read", [&] { return io::read_mesh(o.input); });
    points = m.num_points(), cells = m.num_cells();
    check_memory(o.common, bytes_held(m), o.input + ": convert: the data read");
    progress.say("writing " + o.output);
    timer.run("write", [&] { io::write_mesh(m, o.output); });
  } else {
    const ImageGrid v = timer.run("read", [&] { return io::read_volume(o.input); });
    points = v.num_points();
    check_memory(o.common, v.byte_count(), o.input + ": convert: the samples read");
    r["dims"] = v.dims;
    progress.say("writing " + o.output);
    timer.run("write", [&] { io::write_volume(v, o.output); });
  }
  say_written(o.common, points, cells, "cells", o.output);
  r.update(files_and_counts(o.input, o.output, points, cells));
  r["kind"] = in == Kind::Grid ? "grid" : in == Kind::Surface ? "mesh" : "volume";
  finish_report(o.common, r, threads, timer, PeakRss::Include);
  return 0;
}

Register reg{make_command<ConvertCli>(
    "convert",
    "rewrite a grid (" + io::extensions_of(io::DataKind::Grid, true) + "), surface (" +
        io::extensions_of(io::DataKind::Surface, true) + ") or volume (" + io::extensions_of(io::DataKind::Volume, true) +
        ") in another format",
    add_convert_options, run_convert)};

}  // namespace

}  // namespace keymesh::cli
