// keymesh: connected meshes from finely threaded mesh transformations.
// Exit codes: 0 success, 1 bad input or failed operation, 2 bad usage.
#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdio>
#include <deque>
#include <exception>
#include <new>
#include <iostream>
#include <ostream>
#include <string>

#include "command.hpp"
#include "integer_options.hpp"
#include "keymesh/core/huge_pages.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/io/output_transaction.hpp"

KEYMESH_REEXEC_WITH_HUGE_PAGES_AT_START();

namespace {

namespace dist = keymesh::distributed;
using keymesh::cli::Subcommand;

// Under mpirun every rank parses and checks the same command line alike:
// what they would all say (usage errors, help) is said by rank 0 alone.
bool speaks() { return dist::launched_rank() == 0; }

// An error this rank met alone inside a collective step (no agreement
// possible: the other ranks may wait for it in MPI forever): said once, by
// this rank, then every rank ends (MPI_Abort, exit 1).
int fail_alone(const Subcommand* cmd, const char* message) {
  std::fprintf(stderr, "keymesh: %s\n", keymesh::cli::error_line(cmd, message).c_str());
  if (dist::size() > 1) dist::abort_all(1);
  return 1;
}

// The refusals made before any work, agreed by the ranks: the lowest
// refusing rank's line, said by rank 0, and its exit code on every rank.
int refuse_before_work(const Subcommand& cmd) {
  keymesh::cli::Refusal refusal = keymesh::cli::refuse_shared_paths(cmd);
  if (refusal.code == 0) refusal = keymesh::cli::refuse_unwritable_outputs(cmd);
  // The code (1 or 2) travels as the message's first character.
  const std::string shared = dist::first_error(refusal.code ? std::to_string(refusal.code) + refusal.line : "");
  if (shared.empty()) return 0;
  if (dist::rank() == 0) std::fprintf(stderr, "%s\n", shared.c_str() + 1);
  return shared[0] - '0';
}

// Runs the chosen command: its outputs appear only if it succeeds. One way
// out for errors: one every rank holds (SharedError) is said by rank 0 and
// every rank exits 1; any other ends the run from the rank that met it.
int run_command(const Subcommand* cmd, const std::function<int()>& run) {
  try {
    // Only the voxel contour and labels are distributed; the other
    // operations would each run whole on every rank and race on the output.
    if (dist::size() > 1 && cmd->get_name() != "contour" && cmd->get_name() != "labels") {
      if (dist::rank() == 0)
        std::fprintf(stderr, "keymesh %s: not distributed; under mpirun -np %d only `contour` of a volume "
                             "and `labels` run on several ranks (run %s as one process)\n",
                     cmd->get_name().c_str(), dist::size(), cmd->get_name().c_str());
      return 2;
    }
    if (int rc = refuse_before_work(*cmd)) return rc;
    keymesh::io::OutputTransaction outputs;
    const int rc = run();
    if (rc == 0) outputs.commit();
    return rc;
  } catch (const dist::SharedError& e) {
    if (dist::rank() == 0) std::fprintf(stderr, "keymesh: %s\n", keymesh::cli::error_line(cmd, e.what()).c_str());
    return 1;
  } catch (const std::bad_alloc&) {
    return fail_alone(cmd, "out of memory");
  } catch (const std::exception& e) {
    return fail_alone(cmd, e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  // A pipe or FIFO whose reader goes away is a write error (EPIPE) that the
  // writers report by name and exit 1 on, not a death by signal.
  std::signal(SIGPIPE, SIG_IGN);
  // Under mpirun: MPI for the whole run (a no-op otherwise).
  try {
    dist::init(&argc, &argv);
  } catch (const std::exception& e) {  // MPI's module missing
    if (speaks()) std::fprintf(stderr, "keymesh: %s\n", e.what());
    return 1;
  }
  struct Finalize {
    ~Finalize() { dist::finalize(); }
  } finalize;
  CLI::App app{"keymesh: turns triangle soup from threaded mesh generators into connected meshes\n"
               "by keying every generated element on the input element that produced it."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "keymesh 0.1.0");
  std::deque<Subcommand> subs;  // each subcommand's options, declared by its file
  std::vector<std::pair<Subcommand*, std::function<int()>>> runners;
  for (auto& command : keymesh::cli::registry()) {
    Subcommand& sub = subs.emplace_back(*app.add_subcommand(command.name, command.description));
    runners.emplace_back(&sub, command.setup(sub));
    keymesh::cli::refuse_out_of_range_integers(sub);
  }
  std::ostream silent(nullptr);  // the other ranks' copy of rank 0's usage lines
  std::ostream& out = speaks() ? std::cout : silent;
  std::ostream& err = speaks() ? std::cerr : silent;
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e, out, err);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e, out, err);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e, out, err);
  } catch (const CLI::ParseError& e) {
    app.exit(e, out, err);
    return 2;
  }
  if (dist::launched_size() > 1 && !dist::compiled()) {
    if (speaks())
      std::fprintf(stderr, "keymesh: started by mpirun with %d ranks, but this keymesh was built without MPI "
                           "(install libopenmpi-dev and rebuild)\n", dist::launched_size());
    return 2;
  }
  for (auto& [sub, run] : runners)
    if (sub->parsed()) return run_command(sub, run);
  return 2;
}
