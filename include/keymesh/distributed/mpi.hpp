#pragma once
// The MPI environment of a distributed run (issue 9): `mpirun -np P keymesh ...`.
//
// keymesh is one executable for both worlds: it calls MPI_Init only when a
// launcher started it (mpirun/mpiexec of OpenMPI, MPICH or a PMI/PMIx
// launcher), so plain runs never touch MPI. Without an MPI build
// (KEYMESH_HAVE_MPI undefined) the same functions describe a world of one
// rank, and a multi-rank launch is refused by name.

#include <cstddef>
#include <vector>

namespace keymesh::distributed {

// True when keymesh was built with MPI.
bool compiled();
// True when this process was started by mpirun/mpiexec (OpenMPI, MPICH, PMI).
bool launched_by_mpi();
// Ranks the launcher started, from its environment (1 when not launched);
// readable before init().
int launched_size();
// MPI_Init / MPI_Finalize around main, only when launched by mpirun.
void init(int* argc, char*** argv);
void finalize();
int rank();
int size();
// Ends every rank after an error on one (MPI_Abort), with `code`.
[[noreturn]] void abort_all(int code);
// Collective: true when every rank passes true (how ranks agree that all
// their pieces were written before rank 0 writes the index).
bool all_ok(bool ok);
// Collective: every rank's bytes, in rank order, on every rank (small
// tables: LimitError past 2^31 - 1 bytes in all) or on rank 0 only (any
// size, sent in pieces; the other ranks get an empty list). A world of one
// rank returns {mine}.
std::vector<std::vector<std::byte>> all_gather_bytes(const std::vector<std::byte>& mine);
std::vector<std::vector<std::byte>> gather_bytes(const std::vector<std::byte>& mine);

}  // namespace keymesh::distributed
