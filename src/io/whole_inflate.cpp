#include "whole_inflate.hpp"

#include <libdeflate.h>
#include <sys/mman.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <memory>

#include "keymesh/io/input_file.hpp"
#include "volume_formats.hpp"

namespace keymesh::io::detail {

namespace {

constexpr std::size_t kMemberOverhead = 18;  // a gzip member's 10-byte header and 8-byte trailer
constexpr unsigned char kHeaderCrcFlag = 0x02;  // FHCRC

// The file read-only in memory: its pages are the page cache's, so holding
// the compressed bytes costs no copy and no anonymous memory. (A file cut
// short by another process while it is mapped would raise SIGBUS; no reader
// guards against a file changing under it.)
class MappedFile {
 public:
  explicit MappedFile(const std::string& path) {
    InputFile in(path);
    size_ = in.size();
    if (size_ == 0 || size_ > std::numeric_limits<std::size_t>::max()) return;
    void* p = ::mmap(nullptr, static_cast<std::size_t>(size_), PROT_READ, MAP_PRIVATE | MAP_POPULATE,
                     fileno(in.stream()), 0);
    if (p != MAP_FAILED) data_ = static_cast<const unsigned char*>(p);
  }
  ~MappedFile() {
    if (data_) ::munmap(const_cast<unsigned char*>(data_), static_cast<std::size_t>(size_));
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  const unsigned char* data() const { return data_; }  // nullptr when it could not be mapped
  std::uint64_t size() const { return size_; }

 private:
  const unsigned char* data_ = nullptr;
  std::uint64_t size_ = 0;
};

// One decompressor per thread, kept: allocating one per call costs 12 K
// instructions, 5 % of inflating a VTK 32 KiB block.
libdeflate_decompressor* decompressor() {
  thread_local const std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)> d(
      libdeflate_alloc_decompressor(), libdeflate_free_decompressor);
  return d.get();
}

std::uint32_t little_endian_32(const unsigned char* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

// A gzip member libdeflate checks as zlib would: magic bytes, room for a
// header and a trailer, and no header CRC-16 (libdeflate skips it unchecked).
bool member_starts(const unsigned char* p, std::size_t left) {
  return left >= kMemberOverhead && p[0] == 0x1f && p[1] == 0x8b && !(p[3] & kHeaderCrcFlag);
}

}  // namespace

std::optional<Array<std::byte>> inflate_gzip_file(const std::string& path, std::uint64_t offset,
                                                        std::uint64_t skip, std::uint64_t size) {
  const MappedFile file(path);
  if (!file.data() || offset >= file.size()) return std::nullopt;
  const unsigned char* in = file.data() + offset;
  const auto in_size = static_cast<std::size_t>(file.size() - offset);
  const std::uint64_t total = skip + size;
  if (in_size < kMemberOverhead || total > std::numeric_limits<std::size_t>::max()) return std::nullopt;
  // ISIZE, the last member's length modulo 2^32: the whole stream's for the
  // usual single member.
  const bool trailer_agrees = little_endian_32(in + in_size - 4) == static_cast<std::uint32_t>(total);
  Array<std::byte> out(static_cast<std::size_t>(trailer_agrees ? total : initial_inflate_bytes(in_size, total)));
  libdeflate_decompressor* d = decompressor();
  if (!d) return std::nullopt;
  std::size_t read = 0, done = 0;
  while (done < total) {
    if (!member_starts(in + read, in_size - read)) return std::nullopt;
    std::size_t used = 0, got = 0;
    const libdeflate_result r = libdeflate_gzip_decompress_ex(d, in + read, in_size - read, out.data() + done,
                                                              out.size() - done, &used, &got);
    if (r == LIBDEFLATE_SUCCESS) {
      read += used;
      done += got;
    } else if (r == LIBDEFLATE_INSUFFICIENT_SPACE && out.size() < total) {
      // This member again, with room to double what there is.
      out.resize(static_cast<std::size_t>(std::min<std::uint64_t>(total, 2 * std::uint64_t{out.size()})));
    } else {
      return std::nullopt;
    }
  }
  out.erase(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(skip));
  return out;
}

bool inflate_zlib_exact(const char* src, std::size_t size, char* out, std::size_t expected) {
  libdeflate_decompressor* d = decompressor();
  std::size_t used = 0, got = 0;
  return d && libdeflate_zlib_decompress_ex(d, src, size, out, expected, &used, &got) == LIBDEFLATE_SUCCESS &&
         got == expected;
}

bool inflate_zlib_or_gzip_exact(const char* src, std::size_t size, char* out, std::size_t expected) {
  const auto* in = reinterpret_cast<const unsigned char*>(src);
  if (size < 2 || in[0] != 0x1f || in[1] != 0x8b) return inflate_zlib_exact(src, size, out, expected);
  libdeflate_decompressor* d = decompressor();
  std::size_t used = 0, got = 0;
  return d && member_starts(in, size) &&
         libdeflate_gzip_decompress_ex(d, in, size, out, expected, &used, &got) == LIBDEFLATE_SUCCESS &&
         got == expected;
}

}  // namespace keymesh::io::detail
