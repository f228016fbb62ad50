#include "command.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

#include "keymesh/io/atomic_file.hpp"
#include "keymesh/parallel/threads.hpp"

namespace keymesh::cli {

void add_common_options(CLI::App& cmd, CommonOptions& common) {
  cmd.add_option("--threads", common.threads, "worker threads (0 = all cores)")->check(CLI::NonNegativeNumber);
  cmd.add_option("--report", common.report_path, "write a JSON report of counts and per-stage seconds");
  cmd.add_flag("--quiet,-q", common.quiet, "no progress messages on stderr");
  cmd.add_option("--backend", common.backend, "cpu (threads) or cuda (NVIDIA GPU; output identical to cpu)")
      ->check(CLI::IsMember({"cpu", "cuda"}));
}

int require_cpu_backend(const CommonOptions& common, const char* what) {
  if (common.backend == "cpu") return 0;
  std::fprintf(stderr, "keymesh: --backend cuda: %s is not available on the GPU yet (use --backend cpu)\n", what);
  return 1;
}

int apply_threads(const CommonOptions& common) { return parallel::set_thread_count(common.threads); }

StageTimer::StageTimer() : start_(std::chrono::steady_clock::now()) {}

void StageTimer::add(const std::string& name, double seconds) {
  for (auto& [n, s] : stages_)
    if (n == name) {
      s += seconds;
      return;
    }
  stages_.emplace_back(name, seconds);
}

double StageTimer::total() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

nlohmann::json StageTimer::seconds() const {
  nlohmann::json j = nlohmann::json::object();
  j["total"] = total();
  for (const auto& [n, s] : stages_) j[n] = s;
  return j;
}

void Progress::say(const std::string& line) const {
  if (enabled_) std::fprintf(stderr, "keymesh: %s\n", line.c_str());
}

void write_report(const std::string& path, const nlohmann::json& report) {
  io::AtomicFile file(path);
  file.write(report.dump(2));
  file.write("\n");
  file.commit();
}

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

long long file_size(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  return ec ? 0 : static_cast<long long>(size);
}

bool is_mesh_path(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".ply" || ext == ".obj" || ext == ".stl" || ext == ".vtp" || ext == ".pvtp" || ext == ".glb";
}

std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}

}  // namespace keymesh::cli
