#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "keymesh/io/atomic_file.hpp"
#include "keymesh/io/volume_formats.hpp"

namespace keymesh::io {

namespace detail {

std::uint64_t file_size_or_throw(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": no such file");
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read: " + ec.message());
  return static_cast<std::uint64_t>(size);
}

void read_exact(const std::string& path, std::uint64_t offset, void* dst, std::uint64_t size, const std::string& what) {
  const std::uint64_t have = file_size_or_throw(path);
  if (offset > have || size > have - offset)
    throw InputError(path + ": file holds " + std::to_string(have) + " bytes, " + what + " needs " +
                     std::to_string(offset + size));
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path + ": cannot open: " + std::strerror(errno));
  const bool ok = fseeko(f, static_cast<off_t>(offset), SEEK_SET) == 0 &&
                  std::fread(dst, 1, static_cast<std::size_t>(size), f) == static_cast<std::size_t>(size);
  std::fclose(f);
  if (!ok) throw InputError(path + ": read failed (" + what + ")");
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
    grid.allocate(dims, type);
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  } catch (const LimitError& e) {
    throw LimitError(path + ": " + e.what());
  }
}

}  // namespace detail

ImageGrid read_raw(const std::string& path, const RawOptions& o) {
  for (int a = 0; a < 3; ++a)
    if (!(o.spacing[a] > 0) || !std::isfinite(o.spacing[a]))
      throw InputError(path + ": spacing " + std::to_string(o.spacing[a]) + " must be positive");
  if (o.header_bytes < 0) throw InputError(path + ": negative header size");
  // Check the size before allocating: a wrong --dims must not allocate gigabytes.
  const std::uint64_t have = detail::file_size_or_throw(path);
  ImageGrid probe;
  {
    Id count = 1;
    for (int a = 0; a < 3; ++a) {
      if (o.dims[a] <= 0) throw InputError(path + ": --dims must be positive, got " + std::to_string(o.dims[a]));
      if (count > (Id{1} << 56) / o.dims[a]) throw LimitError(path + ": --dims overflow");
      count *= o.dims[a];
    }
    const std::uint64_t need = static_cast<std::uint64_t>(o.header_bytes) +
                               static_cast<std::uint64_t>(count) * scalar_size(o.type);
    if (need > have)
      throw InputError(path + ": file holds " + std::to_string(have) + " bytes, expected " + std::to_string(need) +
                       " for " + std::to_string(o.dims[0]) + "x" + std::to_string(o.dims[1]) + "x" +
                       std::to_string(o.dims[2]) + " " + scalar_type_name(o.type));
  }
  ImageGrid grid;
  detail::allocate_checked(grid, o.dims, o.type, path);
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
