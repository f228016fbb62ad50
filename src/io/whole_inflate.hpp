#pragma once
// Inflation with libdeflate of compressed data held whole in memory, for the
// reads that know how many bytes to expect (a volume's declared samples, a
// VTK XML block's declared size): a few times faster than zlib's streaming inflate, and straight into the
// final buffer. Only the clean case is decided here; whatever is not clean
// (truncated, corrupt, not compressed at all, more data than declared) is
// left to the zlib path in front of which this sits, so that the result or
// the message for it stays the one zlib gives.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "keymesh/core/array.hpp"

namespace keymesh::io::detail {

// The gzip members of `path` from byte `offset` to its end, inflated with
// libdeflate: the first `skip` bytes of the stream are dropped and the next
// `size` returned. std::nullopt unless each member read is well formed (its
// CRC-32 and length checked) and the members end exactly at skip + size
// bytes; the members after that are not looked at, as zlib's gzread does
// not. A member whose header carries a CRC-16 (which libdeflate skips
// without checking) is left to zlib too. The buffer starts at skip + size
// bytes only when the last member's trailer says the stream inflates to
// that; otherwise at zlib's first guess (initial_inflate_bytes), doubling
// as the members need it, so a header that lies costs what it costs zlib.
std::optional<Array<std::byte>> inflate_gzip_file(const std::string& path, std::uint64_t offset,
                                                        std::uint64_t skip, std::uint64_t size);

// One zlib stream (RFC 1950) of `size` bytes inflated with libdeflate into
// out[0, expected): true only when it is well formed (its Adler-32 checked)
// and inflates to exactly `expected` bytes (bytes after the stream are not
// looked at, as zlib's inflate stops at its end); false leaves the decision
// and the message to zlib, and out's bytes are then unspecified.
bool inflate_zlib_exact(const char* src, std::size_t size, char* out, std::size_t expected);
// The same for what zlib's inflateInit2(15 + 32) reads (Zarr's zlib and gzip
// chunks): one gzip member when the stream starts with gzip's magic bytes
// (and carries no header CRC-16), a zlib stream otherwise.
bool inflate_zlib_or_gzip_exact(const char* src, std::size_t size, char* out, std::size_t expected);

}  // namespace keymesh::io::detail
