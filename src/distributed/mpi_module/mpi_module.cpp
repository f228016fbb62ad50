// The MPI module (mpi_api.hpp): the table of libmpi's functions and
// handles, built as libkeymesh_mpi.so, which distributed::init opens when
// an MPI launcher started keymesh.
#include "mpi_api.hpp"

namespace {

const KeymeshMpiApi& table() {
  // Handles are link-time addresses in Open MPI but may be runtime values
  // elsewhere: read once, on first use (after the module is loaded).
  static const KeymeshMpiApi api{kKeymeshMpiApiVersion,
                                 &MPI_Init_thread,
                                 &MPI_Initialized,
                                 &MPI_Finalized,
                                 &MPI_Finalize,
                                 &MPI_Abort,
                                 &MPI_Comm_rank,
                                 &MPI_Comm_size,
                                 &MPI_Barrier,
                                 &MPI_Send,
                                 &MPI_Recv,
                                 &MPI_Allreduce,
                                 &MPI_Allgather,
                                 &MPI_Allgatherv,
                                 &MPI_Alltoall,
                                 &MPI_Alltoallv,
                                 &MPI_Gather,
                                 &MPI_Gatherv,
                                 MPI_COMM_WORLD,
                                 MPI_BYTE,
                                 MPI_INT,
                                 MPI_LONG_LONG,
                                 MPI_UINT32_T,
                                 MPI_UINT64_T,
                                 MPI_FLOAT,
                                 MPI_DOUBLE,
                                 MPI_MIN};
  return api;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) const KeymeshMpiApi* keymesh_mpi_api() { return &table(); }
