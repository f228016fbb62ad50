// keymesh generate sphere --size N -o FILE: the paper's Spherical Distance field.
#include "command.hpp"
#include "keymesh/generate/spherical_distance.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/volume_io.hpp"

namespace keymesh::cli {

namespace {

struct GenerateOptions {
  std::string dataset;
  long long size = 128;
  std::string output;
  CommonOptions common;
};

void add_generate_options(Subcommand& cmd, GenerateOptions& o) {
  cmd.description("write a built-in dataset: `sphere` (Spherical Distance field, float32, size^3)");
  cmd.add_option("dataset", o.dataset, "dataset name")->required()->check(member_of({"sphere"}));
  cmd.add_option("--size,-n", o.size, "points along each axis")->check(in_range(2LL, 1LL << 20));
  cmd.add_option("-o,--output", o.output, "output volume (" + io::accepted_volumes(true) + ")")->required();
  add_common_options(cmd, o.common);
}

int run_generate(const GenerateOptions& o, CommandRun& run) {
  Progress progress(o.common.quiet, o.size >= 384);
  // size^3 float32 samples, held once.
  const std::uint64_t n = static_cast<std::uint64_t>(o.size);
  const std::uint64_t points = saturating_mul(saturating_mul(n, n), n);
  check_work({points, 0, saturating_mul(points, 4)}, memory_budget(o.common),
             o.output + ": generate " + o.dataset + " --size " + std::to_string(o.size));
  progress.say("generating the " + std::to_string(o.size) + "^3 spherical distance field");
  const ImageGrid grid = run.stage("generate", [&] { return generate::spherical_distance(o.size); });
  progress.say("writing " + o.output);
  run.stage("write", [&] { io::write_volume(grid, o.output); });
  nlohmann::json r = {{"dataset", o.dataset}, {"dims", grid.dims}, {"points", grid.num_points()}};
  return run.finish(r, PeakRss::Omit);
}

Register reg{make_cpu_command("generate", "generate", add_generate_options, run_generate)};

}  // namespace

}  // namespace keymesh::cli
