#pragma once
// Writes a file under a temporary name in the same directory and renames it
// over the destination only after everything was written and flushed, so a
// failure (unwritable directory, full disk, exception while encoding) never
// leaves a partial file and never destroys an existing one. A destination
// that is not a regular file (a device, a FIFO) is written in place. Inside
// an OutputTransaction the rename waits for the transaction's commit().
#include <cstddef>
#include <cstdio>
#include <string>
#include <string_view>

namespace keymesh::io {

class AtomicFile {
 public:
  // Creates "<path>.tmp-<pid>-<n>" (its name's head cut when that would pass
  // the file system's name limit); opens an existing FIFO without waiting
  // for a reader (none: refused). Throws InputError naming path on failure.
  explicit AtomicFile(std::string path);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  // Removes the temporary file unless commit() succeeded.
  ~AtomicFile();

  // Appends bytes; throws InputError naming the path on a write error.
  void write(const void* data, std::size_t size);
  void write(std::string_view text) { write(text.data(), text.size()); }
  // Flushes, closes and renames onto the destination (or stages the rename
  // with the open OutputTransaction); throws on failure.
  void commit();

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string temp_path_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
  bool in_place_ = false;  // a device or FIFO: written directly, never renamed
};

}  // namespace keymesh::io
