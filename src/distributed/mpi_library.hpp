#pragma once
// libmpi, through keymesh's MPI module (mpi_module/mpi_api.hpp): what the
// distributed layer calls instead of MPI_* and reads instead of the
// handles (mpi().comm_world for MPI_COMM_WORLD, mpi().byte for MPI_BYTE ...).
#include "mpi_module/mpi_api.hpp"

namespace keymesh::distributed {

// The table; the module is opened by the first call (distributed::init
// under an MPI launcher), an InputError naming the file when it is missing.
const KeymeshMpiApi& mpi();
// Whether the module is open: a run no launcher started never opens it.
bool mpi_opened();

}  // namespace keymesh::distributed
