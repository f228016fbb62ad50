#pragma once
// --report: the JSON file a command writes beside its output, and the
// summary line on stderr. Each command adds the keys only it knows; the part
// every report shares (the files and counts, threads, per-stage seconds,
// peak memory) is built here, once.
#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace keymesh::cli {

struct CommonOptions;

// Wall-clock stages in the order they ran, for --report "seconds".
class StageTimer {
 public:
  StageTimer();
  // Runs f() as stage `name` and records its duration.
  template <class F>
  decltype(auto) run(const std::string& name, F&& f) {
    const auto t0 = std::chrono::steady_clock::now();
    struct Record {
      StageTimer* timer;
      std::string name;
      std::chrono::steady_clock::time_point t0;
      ~Record() { timer->add(name, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()); }
    } record{this, name, t0};
    return f();
  }
  void add(const std::string& name, double seconds);
  // {"total": ..., "<stage>": ..., ...}
  nlohmann::json seconds() const;
  double total() const;

 private:
  std::chrono::steady_clock::time_point start_;
  std::vector<std::pair<std::string, double>> stages_;
};

// Peak resident set size of this process in MiB.
double peak_rss_mib();

// Writes the report atomically (temporary file, then rename).
void write_report(const std::string& path, const nlohmann::json& report);

// {"input", "output", "points", "cells"}: what was read, what was written
// and its size ("output" left out when empty: commands that write nothing).
nlohmann::json files_and_counts(const std::string& input, const std::string& output, long long points,
                                long long cells);

// The visitor that stores each (name, value) of analyze/ and
// generate/report_fields.hpp in `report`: visit_fields(stats, into(report)).
inline auto into(nlohmann::json& report) {
  return [&report](const char* name, const auto& value) { report[name] = value; };
}

// Whether a report carries "peak_rss_mib" (the commands that hold whole
// volumes or meshes do; the light ones never did).
enum class PeakRss { Omit, Include };

// Adds "threads", "seconds" and (PeakRss::Include) "peak_rss_mib" to
// `report` and writes it when --report was given.
void finish_report(const CommonOptions& common, nlohmann::json report, int threads, const StageTimer& timer,
                   PeakRss peak);

// "keymesh: P points, C <cells_word> -> OUT" on stderr, unless --quiet.
void say_written(const CommonOptions& common, long long points, long long cells, const char* cells_word,
                 const std::string& output);

}  // namespace keymesh::cli
