// keymesh labels IN -o OUT [...]: welded surfaces of a label map.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "command.hpp"
#include "raw_input.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/generate/labels.hpp"
#include "keymesh/generate/labels_stream.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/plane_source.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

namespace {

struct LabelsCli {
  std::string input, output;
  std::string method = "surfacenets";
  std::vector<long long> labels;
  long long background = 0;
  bool per_label = false;
  int smooth = 16;
  double relaxation = 0.5;
  std::string memory_limit;  // stream the volume in slabs
  RawInputCli raw_input;
  CommonOptions common;
};

generate::LabelOptions label_options(const LabelsCli& o) {
  generate::LabelOptions opt;
  opt.method = o.method == "discrete-mc" ? generate::LabelMethod::DiscreteMarchingCubes
                                         : generate::LabelMethod::SurfaceNets;
  opt.labels.assign(o.labels.begin(), o.labels.end());
  opt.background = o.background;
  opt.per_label = o.per_label;
  opt.smooth_iterations = o.smooth;
  opt.relaxation = o.relaxation;
  return opt;
}

Register reg{Command{
    "labels", "surfaces of a label map (segmentation): surface nets or discrete marching cubes, welded by keys",
    [](CLI::App& cmd) -> std::function<int()> {
      auto o = std::make_shared<LabelsCli>();
      cmd.add_option("input", o->input,
                     "integer volume (uint8 int8 uint16 int16 int32): .vti .nrrd .nhdr .nii .nii.gz .den, a DICOM or "
                     "Zarr folder, or raw with --dims")
          ->required();
      cmd.add_option("-o,--output", o->output,
                     "output mesh: .vtp keeps the cell fields boundary_labels (and label); .ply .obj .stl drop them")
          ->required();
      cmd.add_option("--method", o->method,
                     "surfacenets (a point per cell of mixed labels, a quad per edge between two labels, every "
                     "interface once; default) or discrete-mc (each label's marching cubes at edge midpoints, "
                     "as vtkDiscreteFlyingEdges3D)")
          ->check(CLI::IsMember({"surfacenets", "discrete-mc"}));
      cmd.add_option("--labels", o->labels, "labels to extract, e.g. 3,17 (default: every label but the background); "
                                            "the others count as background")
          ->delimiter(',');
      cmd.add_option("--background", o->background, "the background label (default 0)");
      cmd.add_flag("--per-label", o->per_label,
                   "each label's closed surface with its own points (cell field label), instead of one network");
      cmd.add_option("--smooth", o->smooth,
                     "smoothing iterations (default 16; 0 = off): constrained to each point's cell for surface nets, "
                     "Taubin for discrete-mc")
          ->check(CLI::NonNegativeNumber);
      cmd.add_option("--relaxation", o->relaxation, "smoothing relaxation factor in (0, 1] (default 0.5)")
          ->check(CLI::Range(1e-9, 1.0));
      o->raw_input.add_options(cmd, "uint8 int8 uint16 int16 int32");
      cmd.add_option("--memory-limit", o->memory_limit,
                     "stream the input volume in slabs of z-planes holding at most SIZE bytes of samples and 16-bit "
                     "label indices (e.g. 256M); the surfaces are merged by key, then smoothed and written whole "
                     "(not streamed: the output mesh); byte-identical to one in-memory run; raw (--dims), "
                     ".nrrd/.nhdr or .nii with uncompressed samples, DICOM, Zarr")
          ->check(size_validator());
      add_common_options(cmd, o->common);
      return [o]() {
        if (int refused = require_cpu_backend(o->common, "labels")) return refused;
        const int threads = apply_threads(o->common);
        StageTimer timer;
        Progress progress(o->common.quiet, file_size(o->input) > (64ll << 20));
        const generate::LabelOptions opt = label_options(*o);
        const io::RawOptions raw = o->raw_input.given() ? o->raw_input.options() : io::RawOptions{};
        generate::LabelStats stats;
        SurfaceMesh mesh;
        nlohmann::json r;
        try {
          if (!o->memory_limit.empty()) {
            std::size_t limit = 0;
            parse_size(o->memory_limit, limit);  // checked by its validator
            auto source = io::open_volume_planes(o->input, o->raw_input.given() ? &raw : nullptr);
            generate::LabelStreamStats ss;
            mesh = timer.run("labels", [&] {
              return generate::contour_labels_streamed(*source, opt, limit, &stats, &ss);
            });
            timer.add("read", ss.read);
            r["dims"] = source->header().dims;
            r["scalar_type"] = scalar_type_name(source->header().type);
            r["memory_limit"] = limit;
            r["stream"] = {{"slabs", ss.slabs}, {"rows_per_slab", ss.rows_per_slab}, {"slab_bytes", ss.slab_bytes},
                           {"read", ss.read}, {"merge", ss.merge}};
          } else {
            progress.say("reading " + o->input);
            const ImageGrid grid =
                timer.run("read", [&] { return io::read_volume(o->input, o->raw_input.given() ? &raw : nullptr); });
            progress.enable_if(grid.num_points() > (1ll << 25));
            mesh = timer.run("labels", [&] { return generate::contour_labels(grid, opt, &stats); });
            r["dims"] = grid.dims;
            r["scalar_type"] = scalar_type_name(grid.type);
          }
        } catch (const InputError& e) {
          // The generator's refusals name the file the label map came from
          // (the readers' already do).
          if (std::string(e.what()).rfind("labels", 0) == 0) throw InputError(o->input + ": " + e.what());
          throw;
        }
        std::string ext = std::filesystem::path(o->output).extension().string();
        if (ext != ".vtp" && !o->common.quiet)
          std::fprintf(stderr, "keymesh: warning: %s: %s files have no cell data; boundary_labels is not written "
                               "(use .vtp)\n", o->output.c_str(), ext.c_str());
        progress.say("writing " + o->output);
        timer.run("write", [&] { io::write_mesh(mesh, o->output); });
        if (!o->common.quiet)
          std::fprintf(stderr, "keymesh: %lld labels, %lld points, %lld triangles -> %s\n",
                       static_cast<long long>(stats.surfaces), static_cast<long long>(mesh.num_points()),
                       static_cast<long long>(mesh.num_cells()), o->output.c_str());
        if (!o->common.report_path.empty()) {
          r["input"] = o->input;
          r["output"] = o->output;
          r["method"] = o->method;
          r["per_label"] = o->per_label;
          r["background"] = o->background;
          r["smooth"] = o->smooth;
          r["relaxation"] = o->relaxation;
          r["distinct_labels"] = stats.distinct_labels;
          r["labels_extracted"] = stats.surfaces;
          r["points"] = mesh.num_points();
          r["cells"] = mesh.num_cells();
          r["soup_points"] = stats.soup_corners;
          r["threads"] = threads;
          nlohmann::json pairs = nlohmann::json::array();
          for (const auto& p : timer.run("count", [&] { return generate::label_pair_counts(mesh); }))
            pairs.push_back({{"labels", {p.first, p.second}}, {"points", p.points}, {"faces", p.faces}});
          r["pairs"] = pairs;
          auto seconds = timer.seconds();
          seconds["labels_stages"] = {{"scan", stats.scan}, {"generate", stats.generate}, {"weld", stats.weld},
                                      {"smooth", stats.smooth}};
          r["seconds"] = seconds;
          r["peak_rss_mib"] = peak_rss_mib();
          write_report(o->common.report_path, r);
        }
        return 0;
      };
    }}};

}  // namespace

}  // namespace keymesh::cli
