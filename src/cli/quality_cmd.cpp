// keymesh quality MESH [--report R.json]: the paper's triangle quality.
#include <cstdio>
#include <string>

#include "command.hpp"
#include "keymesh/analyze/quality.hpp"
#include "keymesh/io/mesh_io.hpp"

namespace keymesh::cli {

namespace {

struct QualityCli {
  std::string input;
  CommonOptions common;
};

Register reg{Command{
    "quality", "triangle quality Q = 4 sqrt(3) area / sum of squared edge lengths: min, median, mean, histogram",
    [](CLI::App& cmd) -> std::function<int()> {
      auto o = std::make_shared<QualityCli>();
      cmd.add_option("mesh", o->input, "triangle mesh (.vtp .ply .obj .stl)")->required();
      add_common_options(cmd, o->common);
      return [o]() {
        if (int rc = require_cpu_backend(o->common, "the quality measure")) return rc;
        const int threads = apply_threads(o->common);
        StageTimer timer;
        const SurfaceMesh mesh = timer.run("read", [&] { return io::read_mesh(o->input); });
        const analyze::QualityReport q = timer.run("quality", [&] { return analyze::quality(mesh); });
        std::printf("%s: %lld triangles\n  Q min %.4f, median %.4f, mean %.4f, Q > 0.6: %.1f%%\n", o->input.c_str(),
                    (long long)q.triangles, q.min, q.median, q.mean, 100.0 * q.fraction_above_0_6);
        Id most = 1;
        for (Id c : q.histogram) most = std::max(most, c);
        for (int b = 0; b < 10; ++b)
          std::printf("  %.1f-%.1f %10lld %s\n", b / 10.0, (b + 1) / 10.0, (long long)q.histogram[b],
                      std::string(static_cast<std::size_t>(50 * q.histogram[b] / most), '#').c_str());
        if (!o->common.report_path.empty()) {
          nlohmann::json r;
          r["input"] = o->input;
          r["points"] = mesh.num_points();
          r["cells"] = q.triangles;
          r["min"] = q.min;
          r["median"] = q.median;
          r["mean"] = q.mean;
          r["fraction_above_0_6"] = q.fraction_above_0_6;
          r["histogram"] = q.histogram;
          r["threads"] = threads;
          r["seconds"] = timer.seconds();
          write_report(o->common.report_path, r);
        }
        return 0;
      };
    }}};

}  // namespace

}  // namespace keymesh::cli
