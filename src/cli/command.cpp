#include "command.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "keymesh/core/printable.hpp"
#include "keymesh/core/work_estimate.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/io/formats.hpp"
#include "keymesh/io/input_file.hpp"
#include "keymesh/parallel/threads.hpp"

namespace keymesh::cli {

void add_common_options(Subcommand& cmd, CommonOptions& common) {
  cmd.add_option("--threads", common.threads,
                 "worker threads, 0 (all cores) to " + std::to_string(parallel::max_thread_count()) +
                     " (4 x the hardware threads, at least 64)")
      ->check(in_range(0, parallel::max_thread_count()));
  cmd.add_option("--report", common.report_path, "write a JSON report of counts and per-stage seconds");
  cmd.add_flag("--quiet,-q", common.quiet, "no progress messages on stderr");
  cmd.add_option("--max-memory", common.max_memory,
                 "refuse work estimated to need more than SIZE bytes (e.g. 8G; default: this machine's memory, "
                 "or the address-space limit when lower)")
      ->check(size_validator());
  cmd.add_option("--backend", common.backend, "cpu (threads) or cuda (NVIDIA GPU; output identical to cpu)")
      ->check(one_of<generate::Backend>());
}

int refuse_non_finite_isovalues(const char* command, const std::vector<double>& isovalues) {
  for (double iso : isovalues)
    if (!std::isfinite(iso)) {
      if (distributed::rank() == 0)  // every rank refuses alike; said once
        std::fprintf(stderr, "keymesh %s: --iso %g is not a finite number\n", command, iso);
      return 2;
    }
  return 0;
}

bool parse_size(const std::string& text, std::size_t& out) {
  // Digits only: std::stoull would accept "-5" and wrap it to 2^64 - 5.
  std::size_t digits = 0;
  while (digits < text.size() && std::isdigit(static_cast<unsigned char>(text[digits]))) ++digits;
  if (digits == 0 || digits > 20) return false;
  unsigned long long v = 0;
  try {
    v = std::stoull(text.substr(0, digits));
  } catch (...) {
    return false;
  }
  const std::string unit = text.substr(digits);
  int shift = 0;
  if (unit == "K" || unit == "k" || unit == "KiB") shift = 10;
  else if (unit == "M" || unit == "MiB") shift = 20;
  else if (unit == "G" || unit == "GiB") shift = 30;
  else if (unit == "T" || unit == "TiB") shift = 40;
  else if (!unit.empty()) return false;
  if (v > (~0ull >> shift)) return false;
  out = static_cast<std::size_t>(v << shift);
  return out > 0;
}

Check size_validator() {
  return text_check(
      [](std::string& text) -> std::string {
        std::size_t bytes = 0;
        return parse_size(text, bytes) ? std::string()
                                       : "'" + text + "' is not a size (a positive number of bytes, or e.g. 64K, "
                                                      "512M, 2G)";
      },
      "SIZE");
}

std::uint64_t memory_budget(const CommonOptions& common) {
  std::size_t bytes = 0;
  if (!common.max_memory.empty() && parse_size(common.max_memory, bytes)) return bytes;
  return default_memory_budget();
}

std::uint64_t field_components(const std::vector<Field>& fields) {
  std::uint64_t n = 0;
  for (const Field& f : fields) n += static_cast<std::uint64_t>(std::max(f.components, 0));
  return n;
}

namespace {
std::uint64_t field_bytes(const std::vector<Field>& fields) {
  std::uint64_t n = 0;
  for (const Field& f : fields) n = saturating_add(n, saturating_mul(f.values.size(), sizeof(float)));
  return n;
}
}  // namespace

std::uint64_t bytes_held(const SurfaceMesh& m) {
  return saturating_add(saturating_add(m.points.size() * sizeof(float), m.connectivity.size() * sizeof(PointIndex)),
                        saturating_add(m.offsets.size() * sizeof(std::uint64_t),
                                       saturating_add(field_bytes(m.point_fields), field_bytes(m.cell_fields))));
}

std::uint64_t bytes_held(const UnstructuredGrid& g) {
  return saturating_add(
      saturating_add(g.points.size() * sizeof(float), g.connectivity.size() * (g.connectivity.wide() ? 8u : 4u)),
      saturating_add(g.offsets.size() * sizeof(std::uint64_t) + g.cell_types.size(),
                     saturating_add(field_bytes(g.point_fields), field_bytes(g.cell_fields))));
}

void check_memory(const CommonOptions& common, std::uint64_t bytes, const std::string& what) {
  keymesh::check_memory(bytes, memory_budget(common), what);
}

int require_cpu_backend(const CommonOptions& common, const char* what) {
  if (common.backend == "cpu") return 0;
  if (distributed::rank() == 0)  // every rank refuses alike; said once
    std::fprintf(stderr, "keymesh: --backend cuda: %s is not available on the GPU yet (use --backend cpu)\n", what);
  return 1;
}

int apply_threads(const CommonOptions& common) { return parallel::set_thread_count(common.threads); }

void Progress::say(const std::string& line) const {
  if (enabled_) std::fprintf(stderr, "keymesh: %s\n", printable(line).c_str());
}

long long file_size(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  return ec ? 0 : static_cast<long long>(size);
}

bool is_mesh_path(const std::string& path) {
  const io::Format* format = io::format_by_name(path);
  return format && format->kind == io::DataKind::Surface;
}

std::string volume_inputs() { return io::extensions_of(io::DataKind::Volume, false) + ", " + io::folder_formats(); }

namespace {
// /dev/null given as both -o and --report is fine: a device is written in place.
bool is_device(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode));
}
}  // namespace

// The (option, path) pairs a command was given: its inputs first.
std::vector<std::pair<std::string, std::string>> given_paths(const Subcommand& cmd, bool outputs) {
  std::vector<std::pair<std::string, std::string>> paths;
  for (const char* name : {"input", "mesh", "file", "--output", "--report"}) {
    if (!outputs && name[0] == '-') break;
    if (const Option* opt = cmd.get_option_no_throw(name))
      for (const std::string& value : opt->results())
        if (!value.empty()) paths.emplace_back(opt->get_name(), value);
  }
  return paths;
}

std::string error_line(const Subcommand* cmd, const std::string& message) {
  // One line, whatever bytes the file names in it hold.
  if (!cmd) return printable(message);
  const auto paths = given_paths(*cmd, true);
  for (const auto& [option, path] : paths)
    if (message.find(path) != std::string::npos) return printable(message);
  // The input it concerns; a command with none (generate) names its output.
  return printable(paths.empty() ? message : paths.front().second + ": " + message);
}

namespace {
// Why `path` cannot be written, as the file system would say it before any
// work is done; empty when it can be (as far as can be told).
std::string unwritable_because(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  const std::string dir = parent.empty() ? std::string(".") : parent.string();
  struct stat st {};
  if (path.empty() || path.back() == '/') return "not a file name";
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) return "is a directory";
  // access() on a regular file says "Permission denied" (no search
  // permission): the cause is that it is no directory.
  if (::stat(dir.c_str(), &st) == 0 && !S_ISDIR(st.st_mode)) return dir + " is not a directory";
  if (::access(dir.c_str(), W_OK | X_OK) != 0) return std::strerror(errno);
  return "";
}
}  // namespace

Refusal refuse_unwritable_outputs(const Subcommand& cmd) {
  // `labels --format precomputed` writes a directory: its command checks -o.
  const Option* format = cmd.get_option_no_throw("--format");
  const bool directory = format && format->count() > 0 && format->results().front() == "precomputed";
  for (const char* name : {"--output", "--report"})
    if (const Option* opt = cmd.get_option_no_throw(name); opt && !(directory && name[2] == 'o'))
      for (const std::string& path : opt->results()) {
        if (is_device(path)) continue;
        if (const std::string why = unwritable_because(path); !why.empty())
          return {1, "keymesh: " + printable(path) + ": cannot write: " + printable(why)};
      }
  return {};
}

Refusal refuse_shared_paths(const Subcommand& cmd) {
  std::vector<std::pair<std::string, std::string>> paths;  // (option, path)
  for (auto& [option, path] : given_paths(cmd, true))
    if (!is_device(path)) paths.emplace_back(option, path);
  for (std::size_t i = 0; i < paths.size(); ++i)
    for (std::size_t j = i + 1; j < paths.size(); ++j)
      if (io::same_file(paths[i].second, paths[j].second))
        return {2, "keymesh " + cmd.get_name() + ": " + paths[i].first + " " + printable(paths[i].second) + " and " +
                       paths[j].first + " " + printable(paths[j].second) + " name the same file"};
  return {};
}

std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}

}  // namespace keymesh::cli
