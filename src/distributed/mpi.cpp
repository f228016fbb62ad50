// The MPI environment (keymesh/distributed/mpi.hpp) over a real MPI.
#include "keymesh/distributed/mpi.hpp"

#if defined(KEYMESH_HAVE_MPI)

#include <mpi.h>

#include <cstdlib>

namespace keymesh::distributed {

namespace {
bool initialized() {
  int init = 0, fin = 0;
  MPI_Initialized(&init);
  MPI_Finalized(&fin);
  return init && !fin;
}
}  // namespace

bool compiled() { return true; }

void init(int* argc, char*** argv) {
  if (!launched_by_mpi() || initialized()) return;
  // Only the main thread calls MPI; OpenMP threads work between the calls.
  int provided = 0;
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
}

void finalize() {
  if (initialized()) MPI_Finalize();
}

int rank() {
  int r = 0;
  if (initialized()) MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int size() {
  int s = 1;
  if (initialized()) MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

void abort_all(int code) {
  if (initialized()) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

bool all_ok(bool ok) {
  if (!initialized()) return ok;
  int mine = ok ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  return all == 1;
}

}  // namespace keymesh::distributed

#endif
