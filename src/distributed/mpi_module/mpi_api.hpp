#pragma once
// The MPI functions and handles the distributed layer calls, as one table
// that the MPI module (libkeymesh_mpi.so, built from mpi_module.cpp beside
// this header) fills. Linked in, Open MPI's libmpi and the 7 libraries
// below it were mapped and relocated at every start of keymesh, launched by
// mpirun or not (3.6 M instructions, twice with the huge-page re-exec);
// the module is opened by distributed::init only under a launcher. The
// handles (MPI_COMM_WORLD, the datatypes: in Open MPI addresses of libmpi's
// objects) are read through the table too, so that nothing of keymesh's
// own code refers to a symbol of libmpi. Types come from <mpi.h> alone.
#ifndef OMPI_SKIP_MPICXX
#define OMPI_SKIP_MPICXX 1  // the C interface only: no libmpi_cxx
#endif
#ifndef MPICH_SKIP_MPICXX
#define MPICH_SKIP_MPICXX 1
#endif
#include <mpi.h>

#include <cstdint>

extern "C" {

// Bumped with every change of this file (a module of another build is
// refused by name).
inline constexpr std::uint32_t kKeymeshMpiApiVersion = 1;

struct KeymeshMpiApi {
  std::uint32_t version;
  decltype(&MPI_Init_thread) Init_thread;
  decltype(&MPI_Initialized) Initialized;
  decltype(&MPI_Finalized) Finalized;
  decltype(&MPI_Finalize) Finalize;
  decltype(&MPI_Abort) Abort;
  decltype(&MPI_Comm_rank) Comm_rank;
  decltype(&MPI_Comm_size) Comm_size;
  decltype(&MPI_Barrier) Barrier;
  decltype(&MPI_Send) Send;
  decltype(&MPI_Recv) Recv;
  decltype(&MPI_Allreduce) Allreduce;
  decltype(&MPI_Allgather) Allgather;
  decltype(&MPI_Allgatherv) Allgatherv;
  decltype(&MPI_Alltoall) Alltoall;
  decltype(&MPI_Alltoallv) Alltoallv;
  decltype(&MPI_Gather) Gather;
  decltype(&MPI_Gatherv) Gatherv;
  MPI_Comm comm_world;
  MPI_Datatype byte, int_, long_long, uint32, uint64, float_, double_;
  MPI_Op min;
};

// The module's one exported entry point.
const KeymeshMpiApi* keymesh_mpi_api();
inline constexpr const char* kKeymeshMpiEntry = "keymesh_mpi_api";

}  // extern "C"
