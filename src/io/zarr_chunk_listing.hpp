#pragma once
// Which chunk files of a Zarr array are present, learnt from directory
// listings, each directory listed once on first use, instead of one stat()
// per chunk: `keymesh info` of an array of 2 x 2048 x 2048 one-voxel chunks,
// none stored, made 8.4 million failed stat() calls (35 s); it now lists
// one directory. A listed entry is a chunk whatever it is (a file, a
// dangling link, a link loop): the reader then opens it and refuses what is
// not a readable file by name. Only a name absent from the listing is an
// absent chunk, which holds fill_value.
#include <string>
#include <unordered_map>
#include <unordered_set>

namespace keymesh::io {

class ZarrChunkListing {
 public:
  // `array`: the folder of the .zarray; `folder`: the input as given, for messages.
  ZarrChunkListing(std::string array, std::string folder) : array_(std::move(array)), folder_(std::move(folder)) {}

  // Whether the chunk key (its indices joined by `separator`, '.' or '/')
  // names an entry of the array: with '/' each level is a directory,
  // listed only when the level above holds it.
  bool present(const std::string& key, char separator);
  // True when the array's folder holds no chunk at all (its only entries are
  // hidden: .zarray, .zattrs): the whole array is fill_value.
  bool none_stored();

 private:
  // The names in one directory of the array ("" is the array's own folder).
  const std::unordered_set<std::string>& entries(const std::string& directory);

  std::string array_, folder_;
  std::unordered_map<std::string, std::unordered_set<std::string>> listed_;
};

}  // namespace keymesh::io
