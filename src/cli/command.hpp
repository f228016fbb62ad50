#pragma once
// Shared plumbing of the `keymesh` subcommands: the registry each subcommand
// file adds itself to, stage timing, progress on stderr and --report JSON.
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/printable.hpp"  // file names in messages: one line whatever they hold
#include "keymesh/core/progress.hpp"
#include "keymesh/core/work_estimate.hpp"
#include "keymesh/generate/option_names.hpp"
#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"
#include "report.hpp"
#include "subcommand.hpp"

namespace keymesh::cli {

// Options every compute subcommand shares.
struct CommonOptions {
  int threads = 0;          // 0 = all cores
  std::string report_path;  // --report
  bool quiet = false;       // --quiet
  std::string backend = "cpu";  // --backend cpu|cuda
  std::string max_memory;       // --max-memory SIZE; empty: the machine's memory
};

// "123", "64K", "256M", "2G" (powers of 1024; also KiB, MiB, GiB, T, TiB) ->
// bytes; false for anything else, zero and values past 2^64 - 1 included.
bool parse_size(const std::string& text, std::size_t& out);

// A check for options that take a size: refused with exit 2 otherwise.
Check size_validator();

// Float values per point of a mesh's fields (for work estimates).
std::uint64_t field_components(const std::vector<Field>& fields);

// Bytes the command may use: --max-memory, or default_memory_budget().
std::uint64_t memory_budget(const CommonOptions& common);

// Bytes a mesh or grid holds in memory: its arrays.
std::uint64_t bytes_held(const SurfaceMesh& mesh);
std::uint64_t bytes_held(const UnstructuredGrid& grid);

// --max-memory for work whose size is known only from what it holds (a
// mesh read, a volume's planes): LimitError "<what> need about B, more than
// the L of --max-memory" when `bytes` pass memory_budget(common).
void check_memory(const CommonOptions& common, std::uint64_t bytes, const std::string& what);

// For subcommands with no GPU path yet: 0 when --backend is cpu, otherwise
// prints why and returns 1 (refused by name, as the backend contract says).
int require_cpu_backend(const CommonOptions& common, const char* what);

void add_common_options(Subcommand& cmd, CommonOptions& common);

// A check that accepts the names of the library's option enum E
// (generate/option_names.hpp), so help lists what the library parses.
template <class E>
Check one_of() {
  return member_of(generate::option_names<E>());
}

// 0 when every --iso is finite; otherwise "keymesh <command>: --iso V is not
// a finite number" and 2 (a usage error, found before any work).
int refuse_non_finite_isovalues(const char* command, const std::vector<double>& isovalues);

// Applies --threads and returns the count in force.
int apply_threads(const CommonOptions& common);

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

// Size of a file in bytes, 0 when it cannot be read.
long long file_size(const std::string& path);

// True when the path's extension names a surface mesh format of the table
// (io/formats.hpp), read or written.
bool is_mesh_path(const std::string& path);

// The volumes a command without raw options (--dims) reads, for its help:
// the table's volume extensions and folder formats.
std::string volume_inputs();

// A command refused before its work: the exit code (0: not refused) and the
// line to print; the caller prints it (under mpirun: rank 0, once).
struct Refusal {
  int code = 0;
  std::string line;
};

// Refuses (exit 2, one line) a command whose input, -o/--output and --report
// name the same file in any pair: compared by device and inode, and for
// outputs that do not exist yet by resolved directory and name. Looks for
// the options by name (positional "input", "mesh" or "file"; "--output",
// "--report"), so a new subcommand that uses these names is covered.
Refusal refuse_shared_paths(const Subcommand& cmd);

// Refuses (exit 1, one line "<path>: cannot write: <errno text>") a command
// whose -o/--report lies in a directory that does not exist or cannot be
// written, before any work: a report that cannot be written would otherwise
// fail only after the whole run (and after its summary line).
Refusal refuse_unwritable_outputs(const Subcommand& cmd);

// The error line for a failure of `cmd`: the message as it is when it names
// one of the command's paths, otherwise prefixed with the input path
// ("quality: cell 0 is not a triangle" -> "<file>: quality: cell 0 ..."), so
// every line says which file it concerns.
std::string error_line(const Subcommand* cmd, const std::string& message);

// A subcommand: set up its options on `app`, and the function run when chosen.
struct Command {
  std::string name;
  std::string description;
  std::function<std::function<int()>(Subcommand&)> setup;
};

std::vector<Command>& registry();

// A subcommand made of its options struct and two functions: `add_options`
// declares the options on the subcommand, `run` gets them once parsed and
// returns the exit code.
template <class Options>
Command make_command(std::string name, std::string description, void (*add_options)(Subcommand&, Options&),
                     int (*run)(const Options&)) {
  return Command{std::move(name), std::move(description), [add_options, run](Subcommand& cmd) -> std::function<int()> {
                   auto options = std::make_shared<Options>();
                   add_options(cmd, *options);
                   return [options, run] { return run(*options); };
                 }};
}

// The frame of a compute subcommand's run, set up before its own work:
// --threads applied and the stages' timer started; finish() ends every run
// that gets through, with its --report.
class CommandRun {
 public:
  explicit CommandRun(const CommonOptions& common) : common_(common), threads_(apply_threads(common)) {}
  int threads() const { return threads_; }
  // Runs f() as stage `name` of the report's "seconds".
  template <class F>
  decltype(auto) stage(const std::string& name, F&& f) {
    return timer_.run(name, std::forward<F>(f));
  }
  // finish_report (report.hpp) with this run's threads and stage times;
  // returns 0, the exit code of a run that got this far.
  int finish(nlohmann::json report, PeakRss peak) const {
    finish_report(common_, std::move(report), threads_, timer_, peak);
    return 0;
  }

 private:
  const CommonOptions& common_;
  int threads_;
  StageTimer timer_;
};

// A compute subcommand described by `add_options` (its help:
// cmd.description() and the options): when chosen, `run` gets the parsed
// options and a CommandRun. Its --backend is `run`'s to honour.
template <class Options>
Command make_run_command(std::string name, void (*add_options)(Subcommand&, Options&),
                         int (*run)(const Options&, CommandRun&)) {
  return Command{std::move(name), "", [add_options, run](Subcommand& cmd) -> std::function<int()> {
                   auto options = std::make_shared<Options>();
                   add_options(cmd, *options);
                   return [options, run] {
                     CommandRun frame(options->common);
                     return run(*options, frame);
                   };
                 }};
}

// A subcommand with no GPU path, as make_run_command, but --backend other
// than cpu is refused naming `what` (require_cpu_backend) before `run`.
template <class Options>
Command make_cpu_command(std::string name, const char* what, void (*add_options)(Subcommand&, Options&),
                         int (*run)(const Options&, CommandRun&)) {
  return Command{std::move(name), "", [what, add_options, run](Subcommand& cmd) -> std::function<int()> {
                   auto options = std::make_shared<Options>();
                   add_options(cmd, *options);
                   return [options, what, run] {
                     if (int rc = require_cpu_backend(options->common, what)) return rc;
                     CommandRun frame(options->common);
                     return run(*options, frame);
                   };
                 }};
}

struct Register {
  explicit Register(Command c) { registry().push_back(std::move(c)); }
};

}  // namespace keymesh::cli
