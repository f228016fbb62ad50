#include "keymesh/io/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "keymesh/core/error.hpp"

namespace keymesh::io {

namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a file";
}

}  // namespace

InputFile::InputFile(std::string path) : path_(std::move(path)) {
  // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer
  // before fstat could tell us what it is.
  const int fd = ::open(path_.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    if (errno == ENOENT) throw InputError(path_ + ": no such file");
    throw InputError(path_ + ": cannot open: " + std::strerror(errno));
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    const int err = errno;
    const bool stat_failed = !S_ISREG(st.st_mode) && st.st_mode == 0;
    ::close(fd);
    if (stat_failed) throw InputError(path_ + ": cannot read: " + std::strerror(err));
    throw InputError(path_ + ": not a regular file (" + kind_of(st.st_mode) + ")");
  }
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  size_ = static_cast<std::uint64_t>(st.st_size);
  file_ = ::fdopen(fd, "rb");
  if (!file_) {
    ::close(fd);
    throw InputError(path_ + ": cannot open: " + std::strerror(errno));
  }
}

InputFile::~InputFile() {
  if (file_) std::fclose(file_);
}

void InputFile::read_at(std::uint64_t offset, void* dst, std::uint64_t size, const std::string& what) {
  if (offset > size_ || size > size_ - offset)
    throw InputError(path_ + ": file holds " + std::to_string(size_) + " bytes, " + what + " needs " +
                     std::to_string(offset + size));
  const bool ok = fseeko(file_, static_cast<off_t>(offset), SEEK_SET) == 0 &&
                  std::fread(dst, 1, static_cast<std::size_t>(size), file_) == static_cast<std::size_t>(size);
  if (!ok) throw InputError(path_ + ": read failed (" + what + ")");
}

std::uint64_t input_size(const std::string& path) { return InputFile(path).size(); }

std::string file_identity(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) return "inode " + std::to_string(st.st_dev) + " " + std::to_string(st.st_ino);
  // Not there yet: the same name in the same (resolved) directory.
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path p(path);
  fs::path dir = p.parent_path();
  if (dir.empty()) dir = ".";
  const fs::path resolved = fs::weakly_canonical(dir, ec);
  return "path " + (ec ? dir.lexically_normal() : resolved).string() + std::string(1, '\0') + p.filename().string();
}

bool same_file(const std::string& a, const std::string& b) { return file_identity(a) == file_identity(b); }

}  // namespace keymesh::io
