#include "keymesh/io/atomic_file.hpp"

#include <fcntl.h>
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

// The longest file name `directory` holds (pathconf's NAME_MAX; 255 when it
// cannot say).
std::size_t name_max(const std::string& directory) {
  const long n = ::pathconf(directory.c_str(), _PC_NAME_MAX);
  return n > 0 ? static_cast<std::size_t>(n) : 255;
}

// "<name>.tmp-<pid>-<n>" beside `path`; when that passes the file system's
// name limit (a valid 249-byte name did), the name's head is cut so that it
// fits: the suffix alone keeps it unique within this process, and the file
// is created exclusively, so another process's file is never taken over.
std::string temporary_name(const std::string& path, int counter) {
  std::string suffix = ".tmp-";
  suffix.append(std::to_string(::getpid())).append("-").append(std::to_string(counter));
  const std::size_t slash = path.rfind('/');
  const std::string directory = slash == std::string::npos ? "." : path.substr(0, slash + 1);
  const std::size_t name_begin = slash == std::string::npos ? 0 : slash + 1;
  const std::size_t limit = name_max(directory);
  std::string name = path.substr(name_begin);
  // Said now, not by the rename after all the work.
  if (name.size() > limit)
    throw InputError(path + ": cannot write: File name too long (" + std::to_string(name.size()) +
                     " bytes, the file system allows " + std::to_string(limit) + ")");
  if (name.size() + suffix.size() > limit) name.resize(limit > suffix.size() ? limit - suffix.size() : 0);
  return path.substr(0, name_begin) + name + suffix;
}

// An existing FIFO opened for writing: without O_NONBLOCK, open() waits
// for a reader forever; with it, no reader is ENXIO, refused by name.
std::FILE* open_fifo(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    if (errno == ENXIO) throw InputError(path + ": cannot write: a FIFO with no reader");
    throw InputError(path + ": cannot write: " + errno_text());
  }
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);  // the writes then wait for the reader, as a pipe's do
  std::FILE* file = ::fdopen(fd, "wb");
  if (!file) {
    ::close(fd);
    throw InputError(path + ": cannot write: " + errno_text());
  }
  return file;
}
}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  // A destination that exists and is not a regular file (a device such as
  // /dev/null or /dev/full, a FIFO, /dev/stdout) is written in place: it
  // cannot be half-written, and renaming over it would replace the device.
  struct stat st {};
  if (::stat(path_.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    if (S_ISDIR(st.st_mode)) throw InputError(path_ + ": cannot write: is a directory");
    file_ = S_ISFIFO(st.st_mode) ? open_fifo(path_) : std::fopen(path_.c_str(), "wb");
    if (!file_) throw InputError(path_ + ": cannot write: " + errno_text());
    in_place_ = true;
    return;
  }
  // "x": created, never an existing file opened (a name cut short could
  // meet one).
  do {
    temp_path_ = temporary_name(path_, g_counter++);
    file_ = std::fopen(temp_path_.c_str(), "wbx");
  } while (!file_ && errno == EEXIST);
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
