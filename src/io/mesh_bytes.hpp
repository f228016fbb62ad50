#pragma once
// Byte-level helpers shared by the surface mesh readers and writers (ply, obj,
// stl, vtp): whole-file reading, bounds-checked binary cursors, endian-aware
// loads and stores, base64, zlib, text tokens and mesh validation.
//
// Everything lives in keymesh::io::mesh_bytes so it cannot collide with the
// volume readers' helpers (io/bytes.*), which are written independently.
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include "keymesh/core/array.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/mesh/scalar_type.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::io::mesh_bytes {

// A whole file's bytes, read into storage no zero fill went over first (a
// std::string's would: 78 MB of memset before a 3.7 M-triangle .ply was
// read), and past 4 MiB pages kept from an earlier array
// (core/retained_blocks.hpp). Read as a std::string_view.
class FileBytes {
 public:
  explicit FileBytes(Array<char> bytes) : bytes_(std::move(bytes)) {}
  operator std::string_view() const { return view(); }
  std::string_view view() const { return {bytes_.data(), bytes_.size()}; }
  const char* data() const { return bytes_.data(); }
  std::size_t size() const { return bytes_.size(); }

 private:
  Array<char> bytes_;
};

// Reads a whole file; throws InputError naming the path when it cannot.
FileBytes read_whole_file(const std::string& path);

// ---- endian-aware scalar access ------------------------------------------

template <class T>
T byteswap_value(T v) {
  static_assert(std::is_trivially_copyable_v<T>);
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  for (std::size_t i = 0; i < sizeof(T) / 2; ++i) {
    const unsigned char t = b[i];
    b[i] = b[sizeof(T) - 1 - i];
    b[sizeof(T) - 1 - i] = t;
  }
  std::memcpy(&v, b, sizeof(T));
  return v;
}

// Loads a T stored with the given byte order at p (no alignment needed).
template <class T>
T load(const void* p, bool big_endian) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  const bool native_big = std::endian::native == std::endian::big;
  return (big_endian != native_big && sizeof(T) > 1) ? byteswap_value(v) : v;
}

// Stores v at p (no alignment needed) in little-endian byte order.
template <class T>
void store_le(void* p, T v) {
  if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) v = byteswap_value(v);
  std::memcpy(p, &v, sizeof(T));
}

// Appends v in little-endian byte order.
template <class T>
void append_le(std::string& out, T v) {
  if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) v = byteswap_value(v);
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

// ---- samples of a file's scalar type --------------------------------------

// Loads one value of type s at p as double / as int64 (a UInt64 above
// INT64_MAX or a non-integral float throws via the caller's checks).
double load_as_double(const void* p, ScalarType s, bool big_endian);
// Returns false when the value is not an integer representable as int64.
bool load_as_int64(const void* p, ScalarType s, bool big_endian, std::int64_t& out);

// ---- bounds-checked binary cursor ----------------------------------------

class ByteCursor {
 public:
  ByteCursor(std::string_view data, const std::string& path) : data_(data), path_(path) {}
  std::size_t pos() const { return pos_; }
  std::size_t remaining() const { return data_.size() - pos_; }
  // The bytes at the cursor, for a reader that checks sizes itself and then
  // steps over what it read with take().
  const char* here() const { return data_.data() + pos_; }
  // Throws InputError "<path>: truncated ... (<what>)" unless n bytes remain.
  void need(std::size_t n, std::string_view what) const;
  const char* take(std::size_t n, std::string_view what) {
    need(n, what);
    const char* p = data_.data() + pos_;
    pos_ += n;
    return p;
  }
  template <class T>
  T read(bool big_endian, std::string_view what) {
    return load<T>(take(sizeof(T), what), big_endian);
  }

 private:
  std::string_view data_;
  const std::string& path_;
  std::size_t pos_ = 0;
};

// ---- text tokens ----------------------------------------------------------

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// Whitespace-separated tokens over a text, with line tracking for messages.
class TokenCursor {
 public:
  explicit TokenCursor(std::string_view text) : text_(text) {}
  // Next token, or an empty view at the end of the text.
  std::string_view next();
  // Skips to the start of the next line.
  void skip_line();
  bool at_end();
  std::size_t line() const { return line_; }
  std::size_t pos() const { return pos_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
};

// Parses a whole token as a number; false when it is not one.
bool parse_double(std::string_view token, double& out);
bool parse_int64(std::string_view token, std::int64_t& out);

// ---- base64 ----------------------------------------------------------------

std::string base64_encode(const void* data, std::size_t size);

// Decodes base64 incrementally, group by group, so that separately padded
// pieces (VTK encodes a block header and its data as two base64 runs)
// decode as one byte stream. Whitespace is skipped.
class Base64Reader {
 public:
  Base64Reader(std::string_view text, const std::string& path) : text_(text), path_(path) {}
  // Appends exactly n decoded bytes to out; throws InputError when the text
  // ends first or holds a non-base64 character.
  void read(std::size_t n, std::string& out, std::string_view what);
  // Upper bound of the bytes still decodable: refuses absurd sizes early.
  std::size_t max_remaining() const { return (text_.size() - pos_) / 4 * 3 + 3 + pending_.size(); }

 private:
  bool decode_group();
  std::string_view text_;
  const std::string& path_;
  std::size_t pos_ = 0;
  std::string pending_;  // decoded bytes not yet handed out
  std::size_t pending_at_ = 0;
};

// ---- zlib -----------------------------------------------------------------

// Inflates one zlib stream that must expand to exactly `expected` bytes,
// appending them to out. Throws InputError naming path and `what`.
// `expected` bytes are allocated before inflating: the caller checks that
// `size` compressed bytes can hold them (zlib expands at most ~1032:1).
void zlib_inflate(const char* src, std::size_t size, std::size_t expected, std::string& out,
                  const std::string& path, std::string_view what);

// ---- mesh helpers ---------------------------------------------------------

// Checks what a writer relies on: 3 floats per point, offsets starting at 0,
// non-decreasing and ending at the connectivity size, point ids in range and
// field sizes. Throws InputError naming path.
void validate_mesh(const SurfaceMesh& mesh, const std::string& path);

// Drops `offsets` when every cell is a triangle (the SurfaceMesh convention).
void compact_offsets(SurfaceMesh& mesh);

// "Normals" with 3 components, or null.
const Field* normals_field(const SurfaceMesh& mesh);

// Shortest decimal text that reads back as the same float.
void append_float_text(std::string& out, float v);
void append_uint_text(std::string& out, std::uint64_t v);

}  // namespace keymesh::io::mesh_bytes
