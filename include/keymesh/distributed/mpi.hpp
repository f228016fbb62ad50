#pragma once
// The MPI environment of a distributed run (issue 9): `mpirun -np P keymesh ...`.
//
// keymesh is one executable for both worlds: it calls MPI_Init only when a
// launcher started it (mpirun/mpiexec of OpenMPI, MPICH or a PMI/PMIx
// launcher), so plain runs never touch MPI. Without an MPI build
// (KEYMESH_HAVE_MPI undefined) the same functions describe a world of one
// rank, and a multi-rank launch is refused by name.

#include <cstddef>
#include <exception>
#include <functional>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

namespace keymesh::distributed {

// True when keymesh was built with MPI.
bool compiled();
// True when this process was started by mpirun/mpiexec (OpenMPI, MPICH, PMI).
bool launched_by_mpi();
// Ranks the launcher started, from its environment (1 when not launched);
// readable before init().
int launched_size();
// Rank this process was started as, from the launcher's environment (0 when
// not launched): who speaks for the run before, or without, init().
int launched_rank();
// MPI_Init / MPI_Finalize around main, only when launched by mpirun.
void init(int* argc, char*** argv);
void finalize();
int rank();
int size();
// Ends every rank after an error on one (MPI_Abort), with `code`: the last
// resort for an error met inside a collective step, where the other ranks
// may wait for this one forever.
[[noreturn]] void abort_all(int code);

// The error of a run, one rank's or several's, that every rank holds alike
// (the same message, thrown at the same point of the run): every rank ends
// the same way and the message is said once, by rank 0 (the CLI's main).
class SharedError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// How ranks agree on errors. A step is local work (no collective call
// inside: a rank that throws would skip it while the others wait in it)
// followed by share(): error_of(f) runs f and returns its error message (""
// when it succeeded); share() is collective and throws SharedError with the
// lowest failing rank's message on every rank when any rank failed.
template <class F>
std::string error_of(F&& f) {
  try {
    f();
    return {};
  } catch (const std::bad_alloc&) {
    return "out of memory";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    return what.empty() ? std::string("unknown error") : what;
  }
}
// Collective: the lowest rank's non-empty message, the same on every rank ("" when none).
std::string first_error(const std::string& mine);
inline void share(const std::string& error) {
  const std::string first = first_error(error);
  if (!first.empty()) throw SharedError(first);
}
// Collective: f() on every rank, then share() of its error.
template <class F>
void agreed(F&& f) {
  share(error_of(f));
}
// Collective: true when every rank passes true (how ranks agree that all
// their pieces were written before rank 0 writes the index).
bool all_ok(bool ok);
// Collective: every rank's bytes, in rank order, on every rank (small
// tables: LimitError past 2^31 - 1 bytes in all) or on rank 0 only (any
// size, sent in pieces; the other ranks get an empty list). A world of one
// rank returns {mine}.
std::vector<std::vector<std::byte>> all_gather_bytes(const std::vector<std::byte>& mine);
std::vector<std::vector<std::byte>> gather_bytes(const std::vector<std::byte>& mine);
// Collective: every rank's bytes to rank 0 in chunks, one rank after
// another, so that no rank holds more than one chunk besides its own data.
// Each rank calls next(chunk) until it returns false: it fills `chunk` (any
// size, empty too) and returns true while it made one. Rank 0 calls
// take(q, chunk) for each of rank q's chunks in order, q = 0, 1, ... P - 1.
void gather_chunks(const std::function<bool(std::vector<std::byte>& chunk)>& next,
                   const std::function<void(int rank, const std::vector<std::byte>& chunk)>& take);

}  // namespace keymesh::distributed
