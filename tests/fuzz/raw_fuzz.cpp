// Fuzz target: the raw reader's options (what --dims, --type, --endian and
// --header-bytes pass) and file together: the first 32 bytes are the
// options (three int64 dims, an int32 header size, a type byte, an endian
// byte), the rest is the file.
#include <cstring>

#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_target.hpp"
#include "io/volume_formats.hpp"

KEYMESH_FUZZ_TARGET(raw) {
  constexpr std::size_t kOptions = 32;
  if (data.size() < kOptions) return;
  keymesh::io::RawOptions o;
  for (int a = 0; a < 3; ++a) std::memcpy(&o.dims[a], data.data() + 8 * a, 8);
  std::int32_t header = 0;
  std::memcpy(&header, data.data() + 24, 4);
  o.header_bytes = header;
  o.type = static_cast<keymesh::ScalarType>(static_cast<unsigned char>(data[28]) % 7);
  o.big_endian = (data[29] & 1) != 0;
  keymesh::fuzz::expect_valid(keymesh::io::read_raw(keymesh::fuzz::temp_file(data.substr(kOptions), ".raw"), o));
}
