#pragma once
// The one way every reader opens a file (volumes, grids, surfaces, the pieces
// of a .pvtp): regular files only, so the size is known before anything is
// read or allocated. A FIFO would block a reader forever, a directory or a
// device (/dev/zero behind a symlink) has no size and would be read until
// memory runs out: each is refused by name instead.
#include <sys/types.h>

#include <cstdint>
#include <cstdio>
#include <string>

namespace keymesh::io {

class InputFile {
 public:
  // Throws InputError "<path>: no such file", "<path>: not a regular file
  // (a directory)", "<path>: cannot open: <errno text>".
  explicit InputFile(std::string path);
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  ~InputFile();

  const std::string& path() const { return path_; }
  // Size in bytes when the file was opened.
  std::uint64_t size() const { return size_; }
  // A buffered stream positioned at the start, owned by this object.
  std::FILE* stream() const { return file_; }
  // Reads exactly `size` bytes at `offset`; InputError naming `what` when the
  // file holds fewer.
  void read_at(std::uint64_t offset, void* dst, std::uint64_t size, const std::string& what);

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  std::uint64_t size_ = 0;
};

// The size of a readable regular file, refused by name as InputFile does.
std::uint64_t input_size(const std::string& path);

// True when two paths name the same file (same device and inode). Either
// may not exist yet: then its resolved parent directory and name decide.
bool same_file(const std::string& a, const std::string& b);

// What same_file compares, as one string: equal for two paths exactly when
// same_file holds, so that many paths can be checked through a hash set.
std::string file_identity(const std::string& path);

}  // namespace keymesh::io
