// keymesh: connected meshes from finely threaded mesh transformations.
// Exit codes: 0 success, 1 bad input or failed operation, 2 bad usage.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <new>

#include "command.hpp"
#include "keymesh/core/huge_pages.hpp"
#include "keymesh/distributed/mpi.hpp"
#include "keymesh/io/output_transaction.hpp"

KEYMESH_REEXEC_WITH_HUGE_PAGES_AT_START();

int main(int argc, char** argv) {
  // Under mpirun: MPI for the whole run (a no-op otherwise).
  try {
    keymesh::distributed::init(&argc, &argv);
  } catch (const std::exception& e) {  // MPI's module missing
    std::fprintf(stderr, "keymesh: %s\n", e.what());
    return 1;
  }
  struct Finalize {
    ~Finalize() { keymesh::distributed::finalize(); }
  } finalize;
  CLI::App app{"keymesh: turns triangle soup from threaded mesh generators into connected meshes\n"
               "by keying every generated element on the input element that produced it."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "keymesh 0.1.0");
  std::function<int()> chosen;
  std::vector<std::pair<CLI::App*, std::function<int()>>> runners;
  for (auto& command : keymesh::cli::registry()) {
    CLI::App* sub = app.add_subcommand(command.name, command.description);
    runners.emplace_back(sub, command.setup(*sub));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  }
  namespace dist = keymesh::distributed;
  if (dist::launched_size() > 1 && !dist::compiled()) {
    std::fprintf(stderr, "keymesh: started by mpirun with %d ranks, but this keymesh was built without MPI "
                         "(install libopenmpi-dev and rebuild)\n", dist::launched_size());
    return 2;
  }
  const CLI::App* chosen_command = nullptr;
  try {
    for (auto& [sub, run] : runners)
      if (sub->parsed()) {
        chosen_command = sub;
        // Only the voxel contour and labels are distributed; the other
        // operations would each run whole on every rank and race on the output.
        if (dist::size() > 1 && sub->get_name() != "contour" && sub->get_name() != "labels") {
          if (dist::rank() == 0)
            std::fprintf(stderr, "keymesh %s: not distributed; under mpirun -np %d only `contour` of a volume "
                                 "and `labels` run on several ranks (run %s as one process)\n",
                         sub->get_name().c_str(), dist::size(), sub->get_name().c_str());
          return 2;
        }
        if (int rc = keymesh::cli::refuse_shared_paths(*sub)) return rc;
        if (int rc = keymesh::cli::refuse_unwritable_outputs(*sub)) return rc;
        // Every file the command writes appears only if it succeeds.
        keymesh::io::OutputTransaction outputs;
        const int rc = run();
        if (rc == 0) outputs.commit();
        return rc;
      }
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "keymesh: %s\n", keymesh::cli::error_line(chosen_command, "out of memory").c_str());
    if (keymesh::distributed::size() > 1) keymesh::distributed::abort_all(1);  // the other ranks wait on us
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "keymesh: %s\n", keymesh::cli::error_line(chosen_command, e.what()).c_str());
    if (keymesh::distributed::size() > 1) keymesh::distributed::abort_all(1);
    return 1;
  }
}
