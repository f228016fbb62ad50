// VolPack density files (.den), as written by denfile.c in libvolpack1-dev:
// a 62-byte header of shorts in the writer's byte order (version 1 tells
// which), map_len (x, y, z) at shorts 25..27, then uint8 samples, x fastest.
#include <cstring>

#include "volume_formats.hpp"

namespace keymesh::io {

ImageGrid read_den(const std::string& path) {
  unsigned char h[62];
  detail::read_exact(path, 0, h, sizeof h, "the 62-byte .den header");
  auto short_at = [&](int index, bool swap) {
    unsigned char b[2] = {h[2 * index], h[2 * index + 1]};
    if (swap) std::swap(b[0], b[1]);
    std::int16_t v;
    std::memcpy(&v, b, 2);
    return v;
  };
  bool swap;
  if (short_at(0, false) == 1) swap = false;
  else if (short_at(0, true) == 1) swap = true;
  else throw InputError(path + ": not a VolPack .den file (bad version number)");
  const std::array<Id, 3> dims{short_at(25, swap), short_at(26, swap), short_at(27, swap)};
  std::int32_t length;
  std::memcpy(&length, h + 58, 4);
  if (swap) length = static_cast<std::int32_t>(__builtin_bswap32(static_cast<std::uint32_t>(length)));
  for (int a = 0; a < 3; ++a)
    if (dims[a] <= 0) throw InputError(path + ": .den map_len[" + std::to_string(a) + "] = " + std::to_string(dims[a]));
  if (static_cast<Id>(length) != dims[0] * dims[1] * dims[2])
    throw InputError(path + ": inconsistent .den header (map_length " + std::to_string(length) + " is not " +
                     std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]) + ")");
  const std::uint64_t have = detail::file_size_or_throw(path);
  if (have < 62 + static_cast<std::uint64_t>(length))
    throw InputError(path + ": file holds " + std::to_string(have) + " bytes, the header declares " +
                     std::to_string(62 + static_cast<std::uint64_t>(length)));
  ImageGrid grid;
  detail::allocate_checked(grid, dims, ScalarType::UInt8, path);
  grid.name = volume_field_name();  // the format stores no name
  detail::read_exact(path, 62, grid.data(), grid.bytes.size(), "the samples");
  return grid;
}

}  // namespace keymesh::io
