#include "zarr_chunk_listing.hpp"

#include <filesystem>
#include <system_error>

#include "keymesh/core/error.hpp"

namespace keymesh::io {

const std::unordered_set<std::string>& ZarrChunkListing::entries(const std::string& directory) {
  const auto found = listed_.find(directory);
  if (found != listed_.end()) return found->second;
  namespace fs = std::filesystem;
  std::unordered_set<std::string> names;
  std::error_code ec;
  const fs::path path = directory.empty() ? fs::path(array_) : fs::path(array_) / directory;
  for (fs::directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec))
    names.insert(it->path().filename().string());
  if (ec)
    throw InputError(folder_ + ": cannot list the chunks in " + (directory.empty() ? std::string("the array") : directory) +
                     ": " + ec.message());
  return listed_.emplace(directory, std::move(names)).first->second;
}

bool ZarrChunkListing::none_stored() {
  for (const std::string& name : entries(""))
    if (name.empty() || name[0] != '.') return false;
  return true;
}

bool ZarrChunkListing::present(const std::string& key, char separator) {
  if (separator != '/') return entries("").count(key) > 0;
  // "z/y/x": "z" in the array's folder, "y" in z's, "x" in z/y's.
  std::string directory;
  std::size_t begin = 0;
  for (std::size_t end = key.find('/'); end != std::string::npos; begin = end + 1, end = key.find('/', begin)) {
    const std::string level = key.substr(begin, end - begin);
    if (entries(directory).count(level) == 0) return false;
    if (!directory.empty()) directory += '/';
    directory += level;
  }
  return entries(directory).count(key.substr(begin)) > 0;
}

}  // namespace keymesh::io
