#include "report.hpp"

#include <sys/resource.h>

#include <cstdio>

#include "command.hpp"
#include "keymesh/io/atomic_file.hpp"

namespace keymesh::cli {

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

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

void write_report(const std::string& path, const nlohmann::json& report) {
  io::AtomicFile file(path);
  file.write(report.dump(2));
  file.write("\n");
  file.commit();
}

nlohmann::json files_and_counts(const std::string& input, const std::string& output, long long points,
                                long long cells) {
  nlohmann::json r = {{"input", input}, {"points", points}, {"cells", cells}};
  if (!output.empty()) r["output"] = output;
  return r;
}

void finish_report(const CommonOptions& common, nlohmann::json report, int threads, const StageTimer& timer,
                   PeakRss peak) {
  if (common.report_path.empty()) return;
  report["threads"] = threads;
  report["seconds"] = timer.seconds();
  if (peak == PeakRss::Include) report["peak_rss_mib"] = peak_rss_mib();
  write_report(common.report_path, report);
}

void say_written(const CommonOptions& common, long long points, long long cells, const char* cells_word,
                 const std::string& output) {
  if (!common.quiet)
    std::fprintf(stderr, "keymesh: %lld points, %lld %s -> %s\n", points, cells, cells_word, printable(output).c_str());
}

}  // namespace keymesh::cli
