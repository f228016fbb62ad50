#include "gzip_plane_reader.hpp"

#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <utility>

#include "keymesh/core/error.hpp"
#include "keymesh/io/input_file.hpp"

namespace keymesh::io {

namespace {
// Planes kept from each read: the next slab starts at most three planes
// back (the plane two slabs share, and a ghost plane on either side).
constexpr Id kKeptPlanes = 3;
}  // namespace

GzipPlaneReader::GzipPlaneReader(std::string path, std::uint64_t file_offset, std::uint64_t skip,
                                 std::uint64_t plane_bytes)
    : path_(std::move(path)), file_offset_(file_offset), skip_(skip), plane_bytes_(plane_bytes) {
  open_at_first_plane();
}

GzipPlaneReader::~GzipPlaneReader() {
  if (gz_) gzclose(static_cast<gzFile>(gz_));
}

void GzipPlaneReader::open_at_first_plane() {
  if (gz_) gzclose(static_cast<gzFile>(gz_));
  gz_ = nullptr;
  // Opened as every input is (regular files only); zlib gets its own
  // descriptor, positioned at the gzip data.
  InputFile in(path_);
  const int fd = ::dup(fileno(in.stream()));
  if (fd < 0) throw InputError(path_ + ": cannot open: " + std::strerror(errno));
  if (::lseek(fd, static_cast<off_t>(file_offset_), SEEK_SET) < 0) {
    ::close(fd);
    throw InputError(path_ + ": cannot seek to the gzip data at byte " + std::to_string(file_offset_));
  }
  gz_ = gzdopen(fd, "rb");
  if (!gz_) {
    ::close(fd);
    throw InputError(path_ + ": cannot open the gzip stream");
  }
  gzbuffer(static_cast<gzFile>(gz_), 1 << 17);
  next_ = 0;
  // The header before the samples, inflated and dropped.
  std::vector<std::byte> sink(static_cast<std::size_t>(std::min<std::uint64_t>(skip_, 1 << 16)));
  for (std::uint64_t left = skip_; left > 0;) {
    const std::uint64_t n = std::min<std::uint64_t>(left, sink.size());
    inflate(sink.data(), n, -1);
    left -= n;
  }
}

void GzipPlaneReader::inflate(std::byte* out, std::uint64_t size, Id plane) {
  const Id last = plane + static_cast<Id>((size + plane_bytes_ - 1) / plane_bytes_) - 1;
  std::uint64_t done = 0;
  while (done < size) {
    const unsigned chunk = static_cast<unsigned>(std::min<std::uint64_t>(size - done, 1u << 30));
    const int got = gzread(static_cast<gzFile>(gz_), out + done, chunk);
    if (got <= 0) {
      int errnum = 0;
      const char* msg = gzerror(static_cast<gzFile>(gz_), &errnum);
      const std::string where = plane < 0 ? "the header before the samples" : "planes " + std::to_string(plane) + ".." + std::to_string(last);
      throw InputError(path_ + ": gzip data ends in " + where +
                       (errnum != Z_OK && errnum != Z_BUF_ERROR && msg ? std::string(" (") + msg + ")" : std::string(" (truncated)")));
    }
    done += static_cast<std::uint64_t>(got);
  }
}

void GzipPlaneReader::discard_planes(Id count) {
  std::vector<std::byte> sink(static_cast<std::size_t>(plane_bytes_));
  for (Id k = 0; k < count; ++k, ++next_) inflate(sink.data(), plane_bytes_, next_);
}

void GzipPlaneReader::read(Id first, Id count, std::byte* out) {
  Id k = first;
  const Id end = first + count;
  // The planes the previous read kept.
  for (; k < end && k >= kept_first_ && k < kept_first_ + kept_count_; ++k)
    std::memcpy(out + static_cast<std::size_t>(k - first) * plane_bytes_,
                kept_.data() + static_cast<std::size_t>(k - kept_first_) * plane_bytes_, plane_bytes_);
  if (k < end) {
    if (k < next_) open_at_first_plane();
    discard_planes(k - next_);
    inflate(out + static_cast<std::size_t>(k - first) * plane_bytes_, static_cast<std::uint64_t>(end - k) * plane_bytes_, k);
    next_ = end;
  }
  kept_count_ = std::min(kKeptPlanes, count);
  kept_first_ = end - kept_count_;
  kept_.assign(out + static_cast<std::size_t>(kept_first_ - first) * plane_bytes_,
               out + static_cast<std::size_t>(count) * plane_bytes_);
}

}  // namespace keymesh::io
