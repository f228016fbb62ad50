// keymesh quality MESH [--report R.json]: the paper's triangle quality.
#include <cstdio>
#include <string>

#include "command.hpp"
#include "keymesh/analyze/report_fields.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/mesh_io.hpp"

namespace keymesh::cli {

namespace {

struct QualityCli {
  std::string input;
  CommonOptions common;
};

void add_quality_options(Subcommand& cmd, QualityCli& o) {
  cmd.description("triangle quality Q = 4 sqrt(3) area / sum of squared edge lengths: min, median, mean, histogram");
  cmd.add_option("mesh", o.input, "triangle mesh (" + io::extensions_of(io::DataKind::Surface, false) + ")")->required();
  add_common_options(cmd, o.common);
}

int run_quality(const QualityCli& o, CommandRun& run) {
  const SurfaceMesh mesh = run.stage("read", [&] { return io::read_mesh(o.input); });
  check_memory(o.common, bytes_held(mesh), o.input + ": quality: the mesh");
  const analyze::QualityReport q = run.stage("quality", [&] { return analyze::quality(mesh); });
  std::printf("%s: %lld triangles\n  Q min %.4f, median %.4f, mean %.4f, Q > 0.6: %.1f%%\n", o.input.c_str(),
              (long long)q.triangles, q.min, q.median, q.mean, 100.0 * q.fraction_above_0_6);
  Id most = 1;
  for (Id c : q.histogram) most = std::max(most, c);
  for (int b = 0; b < 10; ++b)
    std::printf("  %.1f-%.1f %10lld %s\n", b / 10.0, (b + 1) / 10.0, (long long)q.histogram[b],
                std::string(static_cast<std::size_t>(50 * q.histogram[b] / most), '#').c_str());
  nlohmann::json r = {{"input", o.input}, {"points", mesh.num_points()}};
  analyze::visit_fields(q, into(r));
  return run.finish(r, PeakRss::Omit);
}

Register reg{make_cpu_command("quality", "the quality measure", add_quality_options, run_quality)};

}  // namespace

}  // namespace keymesh::cli
