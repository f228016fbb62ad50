#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <cstring>
#include <filesystem>

#include "keymesh/io/atomic_file.hpp"
#include "keymesh/io/input_file.hpp"
#include "volume_formats.hpp"

namespace keymesh::io {

namespace detail {

std::uint64_t file_size_or_throw(const std::string& path) { return input_size(path); }

void read_exact(const std::string& path, std::uint64_t offset, void* dst, std::uint64_t size, const std::string& what) {
  InputFile(path).read_at(offset, dst, size, what);
}

void swap_samples(ImageGrid& grid) {
  const std::size_t s = scalar_size(grid.type);
  if (s == 1) return;
  std::byte* p = grid.bytes.data();
  const std::size_t n = grid.bytes.size() / s;
  for (std::size_t i = 0; i < n; ++i, p += s)
    for (std::size_t a = 0, b = s - 1; a < b; ++a, --b) std::swap(p[a], p[b]);
}

void allocate_checked(ImageGrid& grid, std::array<Id, 3> dims, ScalarType type, const std::string& path) {
  try {
    grid.allocate_unwritten(dims, type);  // the reader writes every sample
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  } catch (const LimitError& e) {
    throw LimitError(path + ": " + e.what());
  }
}

std::uint64_t checked_byte_count(std::array<Id, 3> dims, ScalarType type, const std::string& path) {
  // The same rules as ImageGrid::allocate, without allocating.
  constexpr Id kMax = std::numeric_limits<Id>::max();
  Id count = 1;
  for (int a = 0; a < 3; ++a) {
    if (dims[a] <= 0)
      throw InputError(path + ": grid dimension " + std::to_string(a) + " is " + std::to_string(dims[a]) +
                       " (must be positive)");
    if (count > kMax / dims[a])
      throw LimitError(path + ": grid dimensions " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" +
                       std::to_string(dims[2]) + " overflow a 64-bit point count");
    count *= dims[a];
  }
  const Id size = static_cast<Id>(scalar_size(type));
  if (count > kMax / size / 4) throw LimitError(path + ": grid of " + std::to_string(count) + " points is too large");
  return static_cast<std::uint64_t>(count * size);
}

std::uint64_t initial_inflate_bytes(std::uint64_t compressed_bytes, std::uint64_t size) {
  // Typical volumes compress 2-10:1; a first guess of 4x (plus 64 KiB) takes
  // one allocation for many, and doubling covers the rest.
  if (compressed_bytes > (std::uint64_t{1} << 60) / 4) return size;
  return std::min(size, 4 * compressed_bytes + (64u << 10));
}

Array<std::byte> read_gz_growing(void* gz_file, std::uint64_t size, std::uint64_t compressed_bytes,
                                       const std::string& path, const std::string& what, bool allow_plain) {
  gzFile gz = static_cast<gzFile>(gz_file);
  Array<std::byte> out;
  std::uint64_t done = 0;
  while (done < size) {
    if (done == out.size()) {
      const std::uint64_t grow = out.empty() ? initial_inflate_bytes(compressed_bytes, size) : 2 * out.size();
      out.resize(static_cast<std::size_t>(std::min<std::uint64_t>(size, grow)));
    }
    const unsigned chunk = static_cast<unsigned>(std::min<std::uint64_t>(out.size() - done, 1u << 30));
    const int got = gzread(gz, out.data() + done, chunk);
    if (got <= 0) {
      int code = Z_OK;
      const char* message = gzerror(gz, &code);
      throw InputError(path + ": " + what + " ends after " + std::to_string(done) + " of " + std::to_string(size) +
                       " bytes" + (code != Z_OK && message && *message ? std::string(" (") + message + ")" : ""));
    }
    if (done == 0 && !allow_plain && gzdirect(gz))
      throw InputError(path + ": " + what + " is not gzip-compressed");
    done += static_cast<std::uint64_t>(got);
  }
  return out;
}

void adopt_samples(ImageGrid& grid, std::array<Id, 3> dims, ScalarType type, Array<std::byte> samples) {
  grid.dims = dims;
  grid.type = type;
  grid.bytes = std::move(samples);
}

}  // namespace detail

ImageGrid read_raw(const std::string& path, const RawOptions& o) {
  static const char* const kAxis[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (!(o.spacing[a] > 0) || !std::isfinite(o.spacing[a]))
      throw InputError(path + ": spacing " + kAxis[a] + " = " + std::to_string(o.spacing[a]) +
                       " must be a positive finite number");
    if (!std::isfinite(o.origin[a]))
      throw InputError(path + ": origin " + kAxis[a] + " = " + std::to_string(o.origin[a]) + " must be finite");
    if (o.dims[a] <= 0)
      throw InputError(path + ": --dims " + kAxis[a] + " = " + std::to_string(o.dims[a]) + " must be positive");
  }
  if (o.header_bytes < 0) throw InputError(path + ": --header-bytes " + std::to_string(o.header_bytes) + " is negative");
  // Check the size before allocating: a wrong --dims must not allocate gigabytes.
  const std::uint64_t have = detail::file_size_or_throw(path);
  const std::uint64_t need = static_cast<std::uint64_t>(o.header_bytes) + detail::checked_byte_count(o.dims, o.type, path);
  if (need > have)
    throw InputError(path + ": file holds " + std::to_string(have) + " bytes, expected " + std::to_string(need) +
                     " for " + std::to_string(o.dims[0]) + "x" + std::to_string(o.dims[1]) + "x" +
                     std::to_string(o.dims[2]) + " " + scalar_type_name(o.type) +
                     (o.header_bytes ? " after " + std::to_string(o.header_bytes) + " header bytes" : std::string()));
  ImageGrid grid;
  detail::allocate_checked(grid, o.dims, o.type, path);
  grid.name = volume_field_name();
  grid.spacing = o.spacing;
  grid.origin = o.origin;
  detail::read_exact(path, static_cast<std::uint64_t>(o.header_bytes), grid.data(), grid.bytes.size(), "the samples");
  if (o.big_endian) detail::swap_samples(grid);
  return grid;
}

void write_raw(const ImageGrid& grid, const std::string& path) {
  AtomicFile f(path);
  f.write(grid.data(), grid.bytes.size());
  f.commit();
}

}  // namespace keymesh::io
