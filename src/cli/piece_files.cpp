// The files of a mesh written in pieces (piece_files.hpp).
#include "piece_files.hpp"

#include <filesystem>

#include "keymesh/core/error.hpp"
#include "keymesh/distributed/mpi.hpp"

namespace keymesh::cli {

void write_piece_files(const SurfaceMesh& piece, const std::vector<std::uint64_t>& global_ids,
                       const io::PieceGhosts& ghosts, const std::string& output,
                       const std::vector<io::UInt64PointArray>& uint64_arrays) {
  namespace fs = std::filesystem;
  const int rank = distributed::rank(), ranks = distributed::size();
  const fs::path index(output);
  const std::string stem = index.stem().string();
  auto piece_name = [&](int q) { return stem + "_" + std::to_string(q) + ".vtp"; };
  const fs::path mine = index.parent_path() / piece_name(rank);
  try {
    distributed::agreed([&] {
      try {
        io::write_vtp(piece, mine.string(), &global_ids, &ghosts, uint64_arrays);
      } catch (const std::exception& e) {
        throw InputError("rank " + std::to_string(rank) + ": " + e.what());
      }
    });
    distributed::agreed([&] {
      if (rank != 0) return;
      std::vector<std::string> names;
      for (int q = 0; q < ranks; ++q) names.push_back(piece_name(q));
      std::vector<std::string> wide;
      for (const io::UInt64PointArray& a : uint64_arrays) wide.push_back(a.name);
      io::write_pvtp(output, piece, names, true, true, wide);
    });
  } catch (const distributed::SharedError&) {
    std::error_code ec;
    fs::remove(mine, ec);
    throw;
  }
}

}  // namespace keymesh::cli
