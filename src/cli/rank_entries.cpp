#include "rank_entries.hpp"

#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

#include "keymesh/distributed/mpi.hpp"

namespace keymesh::cli {

nlohmann::json gather_rank_entries(const nlohmann::json& mine) {
  const std::string text = mine.dump();
  std::vector<std::byte> bytes(text.size());
  std::memcpy(bytes.data(), text.data(), text.size());
  nlohmann::json all = nlohmann::json::array();
  for (const auto& b : distributed::gather_bytes(bytes))
    all.push_back(nlohmann::json::parse(std::string(reinterpret_cast<const char*>(b.data()), b.size())));
  return all;
}

}  // namespace keymesh::cli
