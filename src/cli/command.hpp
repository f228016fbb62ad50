#pragma once
// Shared plumbing of the `keymesh` subcommands: the registry each subcommand
// file adds itself to, stage timing, progress on stderr and --report JSON.
#include <CLI/CLI.hpp>

#include <chrono>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "keymesh/core/progress.hpp"

namespace keymesh::cli {

// Options every compute subcommand shares.
struct CommonOptions {
  int threads = 0;          // 0 = all cores
  std::string report_path;  // --report
  bool quiet = false;       // --quiet
  std::string backend = "cpu";  // --backend cpu|cuda
};

// For subcommands with no GPU path yet: 0 when --backend is cpu, otherwise
// prints why and returns 1 (refused by name, as the backend contract says).
int require_cpu_backend(const CommonOptions& common, const char* what);

void add_common_options(CLI::App& cmd, CommonOptions& common);

// Applies --threads and returns the count in force.
int apply_threads(const CommonOptions& common);

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

// Progress lines on stderr ("keymesh: reading X"), only for work expected to
// take over about a second and never with --quiet.
// The library's progress hook (core/progress.hpp) is installed for the
// Progress object's lifetime: the stages long operations report are said
// the same way, so the CLI and Python's progress= see the same stages.
class Progress {
 public:
  Progress(bool quiet, bool large)
      : quiet_(quiet), enabled_(!quiet && large),
        hook_([this](const char* stage, double) { say(stage); }) {}
  void say(const std::string& line) const;
  // Turns progress on once the work is known to be large (never with --quiet).
  void enable_if(bool large) { enabled_ = !quiet_ && (enabled_ || large); }

 private:
  bool quiet_;
  bool enabled_;
  progress::ScopedHook hook_;
};

// Writes the report atomically (temporary file, then rename).
void write_report(const std::string& path, const nlohmann::json& report);

// Peak resident set size of this process in MiB.
double peak_rss_mib();

// Size of a file in bytes, 0 when it cannot be read.
long long file_size(const std::string& path);

// True when the path's extension names a mesh format (.ply .obj .stl .vtp).
bool is_mesh_path(const std::string& path);

// A subcommand: set up its options on `app`, and the function run when chosen.
struct Command {
  std::string name;
  std::string description;
  std::function<std::function<int()>(CLI::App&)> setup;
};

std::vector<Command>& registry();

struct Register {
  explicit Register(Command c) { registry().push_back(std::move(c)); }
};

}  // namespace keymesh::cli
