#include "keymesh/io/atomic_file.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

#include "keymesh/core/error.hpp"
#include "keymesh/io/output_transaction.hpp"

namespace keymesh::io {

namespace {
std::atomic<int> g_counter{0};

std::string errno_text() { return std::strerror(errno); }
}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  // A destination that exists and is not a regular file (a device such as
  // /dev/null or /dev/full, a FIFO, /dev/stdout) is written in place: it
  // cannot be half-written, and renaming over it would replace the device.
  struct stat st {};
  if (::stat(path_.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    if (S_ISDIR(st.st_mode)) throw InputError(path_ + ": cannot write: is a directory");
    file_ = std::fopen(path_.c_str(), "wb");
    if (!file_) throw InputError(path_ + ": cannot write: " + errno_text());
    in_place_ = true;
    return;
  }
  temp_path_ = path_ + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(g_counter++);
  file_ = std::fopen(temp_path_.c_str(), "wb");
  if (!file_) throw InputError(path_ + ": cannot write: " + errno_text());
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
  if (!committed_ && !in_place_) std::remove(temp_path_.c_str());
}

void AtomicFile::write(const void* data, std::size_t size) {
  if (size == 0) return;
  if (std::fwrite(data, 1, size, file_) != size)
    throw InputError(path_ + ": write failed: " + errno_text());
}

void AtomicFile::commit() {
  if (std::fflush(file_) != 0) throw InputError(path_ + ": write failed: " + errno_text());
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (rc != 0) throw InputError(path_ + ": write failed: " + errno_text());
  if (in_place_) {
    committed_ = true;
    return;
  }
  if (OutputTransaction* outputs = OutputTransaction::current()) {
    // Renamed with the command's other outputs once it has succeeded.
    committed_ = true;
    outputs->stage(temp_path_, path_);
    return;
  }
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0)
    throw InputError(path_ + ": cannot rename temporary file into place: " + errno_text());
  committed_ = true;
}

}  // namespace keymesh::io
