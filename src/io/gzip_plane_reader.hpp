#pragma once
// Planes of a gzip-compressed volume read in order with one pass of
// decompression (gzip NIfTI, gzip NRRD under --memory-limit): the stream
// only moves forward, and the last few planes of each read are kept so that
// the next slab, which starts one to three planes back (the shared plane
// and the ghost planes), costs no second pass. A read further back rewinds
// the stream and inflates it again up to there (correct, slower: only a
// distributed rank's ghost plane below can ask for it).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "keymesh/core/types.hpp"

namespace keymesh::io {

class GzipPlaneReader {
 public:
  // The gzip stream starts at file_offset of the file (a .nhdr's data file,
  // an attached NRRD's body) and its first `skip` inflated bytes precede the
  // samples (a .nii.gz's header up to vox_offset). Planes of plane_bytes.
  GzipPlaneReader(std::string path, std::uint64_t file_offset, std::uint64_t skip, std::uint64_t plane_bytes);
  ~GzipPlaneReader();
  GzipPlaneReader(const GzipPlaneReader&) = delete;
  GzipPlaneReader& operator=(const GzipPlaneReader&) = delete;

  // Stored bytes of planes [first, first + count) into out; InputError
  // naming the file when the stream is corrupt or ends early.
  void read(Id first, Id count, std::byte* out);

 private:
  void open_at_first_plane();
  void inflate(std::byte* out, std::uint64_t size, Id plane);
  void discard_planes(Id count);

  std::string path_;
  std::uint64_t file_offset_, skip_, plane_bytes_;
  void* gz_ = nullptr;  // gzFile, kept out of this header
  Id next_ = 0;         // the plane the stream is at
  std::vector<std::byte> kept_;  // the last planes read: [kept_first_, kept_first_ + kept_count_)
  Id kept_first_ = 0, kept_count_ = 0;
};

}  // namespace keymesh::io
