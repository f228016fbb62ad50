// keymesh: connected meshes from finely threaded mesh transformations.
// Exit codes: 0 success, 1 bad input or failed operation, 2 bad usage.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <new>

#include "command.hpp"
#include "keymesh/core/huge_pages.hpp"

int main(int argc, char** argv) {
  keymesh::reexec_with_huge_pages(argc, argv);
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
  try {
    for (auto& [sub, run] : runners)
      if (sub->parsed()) return run();
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "keymesh: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "keymesh: %s\n", e.what());
    return 1;
  }
}
