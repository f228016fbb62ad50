#pragma once
// The "per_rank" entries of a distributed run's report (mpirun: labels into
// pieces or one file, contour --coarsen): each rank's JSON object travels
// to rank 0 as its text (distributed::gather_bytes), and rank 0 reads them
// back, so every command sends and reads them the same way.
#include <nlohmann/json.hpp>

namespace keymesh::cli {

// Collective: every rank's entry, in rank order, as a JSON array on rank 0;
// an empty array on the other ranks.
nlohmann::json gather_rank_entries(const nlohmann::json& mine);

}  // namespace keymesh::cli
