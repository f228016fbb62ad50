// keymesh pipeline IN -o OUT --iso V [--coarsen] [--subdivide K] [--dual]
// [--curvature]: the paper's Figure 8 chain in memory, every stage keyed.
#include <cmath>
#include <cstdio>

#include "command.hpp"
#include "keymesh/backend/contour.hpp"
#include "keymesh/generate/contour.hpp"
#include "keymesh/generate/contour_tets.hpp"
#include "keymesh/generate/dual.hpp"
#include "keymesh/generate/subdivide.hpp"
#include "keymesh/io/grid_io.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

namespace {

struct PipelineCli {
  std::string input, output;
  std::vector<double> isovalues;
  bool coarsen = false, curvature = false, dual = false;
  int subdivide = 0;
  std::string scheme = "linear";
  std::string normals = "average";
  CommonOptions common;
};

Register reg{Command{
    "pipeline", "contour, then optionally coarsen, subdivide and take the dual, in memory (the paper's Figure 8)",
    [](CLI::App& cmd) -> std::function<int()> {
      auto o = std::make_shared<PipelineCli>();
      cmd.add_option("input", o->input, "volume (.vti .nrrd .nhdr .nii .nii.gz .den, DICOM/Zarr folder) or tet grid (.vtu .vtk)")
          ->required();
      cmd.add_option("-o,--output", o->output, "output surface (.vtp .ply .obj; .stl without --dual)")->required();
      cmd.add_option("--iso", o->isovalues, "isovalue (repeat for several)")->required()->expected(1, -1);
      cmd.add_flag("--coarsen", o->coarsen, "merge points by nearest grid point during the contour");
      cmd.add_flag("--curvature", o->curvature, "mean curvature from the volume (voxel grids), carried along");
      cmd.add_option("--subdivide", o->subdivide, "levels of 1->4 subdivision")->check(CLI::Range(0, 6));
      cmd.add_option("--scheme", o->scheme, "subdivision positions: linear or bezier")
          ->check(CLI::IsMember({"linear", "bezier"}));
      cmd.add_option("--normals", o->normals, "none, gradient or average (bezier needs normals)")
          ->check(CLI::IsMember({"none", "gradient", "average"}));
      cmd.add_flag("--dual", o->dual, "finish with the dual mesh");
      add_common_options(cmd, o->common);
      return [o]() {
        for (double iso : o->isovalues)
          if (!std::isfinite(iso)) {
            std::fprintf(stderr, "keymesh pipeline: --iso %g is not a finite number\n", iso);
            return 2;
          }
        if (o->scheme == "bezier" && o->normals == "none") {
          std::fprintf(stderr, "keymesh pipeline: --scheme bezier needs --normals average or gradient\n");
          return 2;
        }
        const int threads = apply_threads(o->common);
        StageTimer timer;
        generate::ContourOptions opt;
        opt.isovalues = o->isovalues;
        opt.coarsen = o->coarsen;
        opt.curvature = o->curvature;
        opt.backend = o->common.backend == "cuda" ? generate::Backend::Cuda : generate::Backend::Cpu;
        if (opt.backend == generate::Backend::Cuda && (o->subdivide > 0 || o->dual))
          if (int rc = require_cpu_backend(o->common, "subdivision and the dual")) return rc;
        opt.normals = o->normals == "gradient"  ? generate::ContourNormals::Gradient
                      : o->normals == "average" ? generate::ContourNormals::Average
                                                : generate::ContourNormals::None;
        SurfaceMesh mesh;
        if (io::is_grid_file(o->input)) {
          const UnstructuredGrid g = timer.run("read", [&] { return io::read_grid(o->input); });
          mesh = timer.run("contour", [&] { return generate::contour(g, opt); });
        } else {
          const ImageGrid g = timer.run("read", [&] { return io::read_volume(o->input); });
          mesh = timer.run("contour", [&] { return backend::contour(g, opt); });
        }
        nlohmann::json r;
        r["contour_cells"] = mesh.num_cells();
        if (o->subdivide > 0) {
          generate::SubdivideOptions so;
          so.levels = o->subdivide;
          so.scheme = o->scheme == "bezier" ? generate::SubdivideScheme::Bezier : generate::SubdivideScheme::Linear;
          mesh = timer.run("subdivide", [&] { return generate::subdivide(mesh, so); });
        }
        if (o->dual) mesh = timer.run("dual", [&] { return generate::dual(mesh); });
        timer.run("write", [&] { io::write_mesh(mesh, o->output); });
        if (!o->common.quiet)
          std::fprintf(stderr, "keymesh: %lld points, %lld cells -> %s\n", (long long)mesh.num_points(),
                       (long long)mesh.num_cells(), o->output.c_str());
        if (!o->common.report_path.empty()) {
          r["input"] = o->input;
          r["output"] = o->output;
          r["points"] = mesh.num_points();
          r["cells"] = mesh.num_cells();
          r["threads"] = threads;
          r["seconds"] = timer.seconds();
          r["peak_rss_mib"] = peak_rss_mib();
          write_report(o->common.report_path, r);
        }
        return 0;
      };
    }}};

}  // namespace

}  // namespace keymesh::cli
