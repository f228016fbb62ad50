// How keymesh learns it was started by an MPI launcher: from the launcher's
// environment, before (and without) MPI_Init.
#include <cstdlib>
#include <string>

#include "keymesh/distributed/mpi.hpp"

namespace keymesh::distributed {

namespace {
const char* launcher_size() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"})
    if (const char* v = std::getenv(name)) return v;
  return nullptr;
}
}  // namespace

bool launched_by_mpi() { return launcher_size() != nullptr || std::getenv("PMIX_RANK") != nullptr; }

int launched_size() {
  const char* v = launcher_size();
  if (!v) return launched_by_mpi() ? 2 : 1;  // PMIx without a size: assume several
  const long n = std::strtol(v, nullptr, 10);
  return n > 0 ? static_cast<int>(n) : 1;
}

int launched_rank() {
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK", "MPI_LOCALRANKID"})
    if (const char* v = std::getenv(name)) return static_cast<int>(std::strtol(v, nullptr, 10));
  return 0;
}

}  // namespace keymesh::distributed
