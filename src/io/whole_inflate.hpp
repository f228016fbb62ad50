#pragma once
// Inflation with libdeflate of compressed data held whole in memory, for the
// reads that know how many bytes to expect (a volume's declared samples): a
// few times faster than zlib's streaming inflate, and straight into the
// final buffer. Only the clean case is decided here; whatever is not clean
// (truncated, corrupt, not compressed at all, more data than declared) is
// left to the zlib path in front of which this sits, so that the result or
// the message for it stays the one zlib gives.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

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
std::optional<std::vector<std::byte>> inflate_gzip_file(const std::string& path, std::uint64_t offset,
                                                        std::uint64_t skip, std::uint64_t size);

}  // namespace keymesh::io::detail
