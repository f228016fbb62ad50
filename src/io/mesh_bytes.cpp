#include "mesh_bytes.hpp"

#include "keymesh/io/input_file.hpp"
#include "whole_inflate.hpp"

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>

namespace keymesh::io::mesh_bytes {

FileBytes read_whole_file(const std::string& path) {
  InputFile in(path);
  Array<char> bytes(static_cast<std::size_t>(in.size()));  // unwritten until read
  in.read_at(0, bytes.data(), in.size(), "the whole file");
  return FileBytes(std::move(bytes));
}

double load_as_double(const void* p, ScalarType s, bool big) {
  switch (s) {
    case ScalarType::Int8: return load<std::int8_t>(p, big);
    case ScalarType::UInt8: return load<std::uint8_t>(p, big);
    case ScalarType::Int16: return load<std::int16_t>(p, big);
    case ScalarType::UInt16: return load<std::uint16_t>(p, big);
    case ScalarType::Int32: return load<std::int32_t>(p, big);
    case ScalarType::UInt32: return load<std::uint32_t>(p, big);
    case ScalarType::Int64: return static_cast<double>(load<std::int64_t>(p, big));
    case ScalarType::UInt64: return static_cast<double>(load<std::uint64_t>(p, big));
    case ScalarType::Float32: return load<float>(p, big);
    case ScalarType::Float64: return load<double>(p, big);
  }
  return 0.0;
}

bool load_as_int64(const void* p, ScalarType s, bool big, std::int64_t& out) {
  switch (s) {
    case ScalarType::Int8: out = load<std::int8_t>(p, big); return true;
    case ScalarType::UInt8: out = load<std::uint8_t>(p, big); return true;
    case ScalarType::Int16: out = load<std::int16_t>(p, big); return true;
    case ScalarType::UInt16: out = load<std::uint16_t>(p, big); return true;
    case ScalarType::Int32: out = load<std::int32_t>(p, big); return true;
    case ScalarType::UInt32: out = load<std::uint32_t>(p, big); return true;
    case ScalarType::Int64: out = load<std::int64_t>(p, big); return true;
    case ScalarType::UInt64: {
      const std::uint64_t u = load<std::uint64_t>(p, big);
      if (u > std::uint64_t(std::numeric_limits<std::int64_t>::max())) return false;
      out = static_cast<std::int64_t>(u);
      return true;
    }
    case ScalarType::Float32:
    case ScalarType::Float64: {
      const double d = load_as_double(p, s, big);
      // Index arrays stored as floats happen (old writers); accept only exact integers.
      if (!(d >= -9.0e18 && d <= 9.0e18) || d != std::floor(d)) return false;
      out = static_cast<std::int64_t>(d);
      return true;
    }
  }
  return false;
}

void ByteCursor::need(std::size_t n, std::string_view what) const {
  if (n > remaining())
    throw InputError(path_ + ": truncated file: " + std::string(what) + " needs " + std::to_string(n) +
                     " bytes at offset " + std::to_string(pos_) + ", only " + std::to_string(remaining()) +
                     " left");
}

std::string_view TokenCursor::next() {
  while (pos_ < text_.size() && is_space(text_[pos_])) {
    if (text_[pos_] == '\n') ++line_;
    ++pos_;
  }
  const std::size_t start = pos_;
  while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
  return text_.substr(start, pos_ - start);
}

void TokenCursor::skip_line() {
  while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  if (pos_ < text_.size()) {
    ++pos_;
    ++line_;
  }
}

bool TokenCursor::at_end() {
  while (pos_ < text_.size() && is_space(text_[pos_])) {
    if (text_[pos_] == '\n') ++line_;
    ++pos_;
  }
  return pos_ >= text_.size();
}

bool parse_double(std::string_view t, double& out) {
  if (t.empty()) return false;
  if (t.front() == '+') t.remove_prefix(1);  // from_chars rejects a leading '+'
  const auto r = std::from_chars(t.data(), t.data() + t.size(), out);
  if (r.ec == std::errc::result_out_of_range && r.ptr == t.data() + t.size()) {
    // Denormals and huge values: fall back to strtod, which saturates.
    out = std::strtod(std::string(t).c_str(), nullptr);
    return true;
  }
  return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

bool parse_int64(std::string_view t, std::int64_t& out) {
  if (t.empty()) return false;
  if (t.front() == '+') t.remove_prefix(1);
  const auto r = std::from_chars(t.data(), t.data() + t.size(), out);
  return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

namespace {
constexpr char kBase64Chars[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}
}  // namespace

std::string base64_encode(const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= size; i += 3) {
    const std::uint32_t v = (std::uint32_t(p[i]) << 16) | (std::uint32_t(p[i + 1]) << 8) | p[i + 2];
    out += kBase64Chars[(v >> 18) & 63];
    out += kBase64Chars[(v >> 12) & 63];
    out += kBase64Chars[(v >> 6) & 63];
    out += kBase64Chars[v & 63];
  }
  if (i < size) {
    std::uint32_t v = std::uint32_t(p[i]) << 16;
    if (i + 1 < size) v |= std::uint32_t(p[i + 1]) << 8;
    out += kBase64Chars[(v >> 18) & 63];
    out += kBase64Chars[(v >> 12) & 63];
    out += (i + 1 < size) ? kBase64Chars[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

bool Base64Reader::decode_group() {
  int vals[4];
  int n = 0;
  int pad = 0;
  while (n < 4) {
    while (pos_ < text_.size() && is_space(text_[pos_])) ++pos_;
    if (pos_ >= text_.size()) break;
    const char c = text_[pos_++];
    if (c == '=') {
      vals[n++] = 0;
      ++pad;
      continue;
    }
    const int v = base64_value(c);
    if (v < 0 || pad > 0)
      throw InputError(path_ + ": invalid base64 character at offset " + std::to_string(pos_ - 1));
    vals[n++] = v;
  }
  if (n == 0) return false;
  if (n < 4 || pad > 2) throw InputError(path_ + ": truncated base64 data");
  const std::uint32_t v = (std::uint32_t(vals[0]) << 18) | (std::uint32_t(vals[1]) << 12) |
                          (std::uint32_t(vals[2]) << 6) | std::uint32_t(vals[3]);
  pending_ += static_cast<char>((v >> 16) & 255);
  if (pad < 2) pending_ += static_cast<char>((v >> 8) & 255);
  if (pad < 1) pending_ += static_cast<char>(v & 255);
  return true;
}

void Base64Reader::read(std::size_t n, std::string& out, std::string_view what) {
  if (n > max_remaining())
    throw InputError(path_ + ": truncated base64 data (" + std::string(what) + " needs " + std::to_string(n) +
                     " bytes)");
  out.reserve(out.size() + n);
  while (n > 0) {
    if (pending_at_ == pending_.size()) {
      pending_.clear();
      pending_at_ = 0;
      // Decode a run of groups at a time; each group yields at most 3 bytes.
      while (pending_.size() < std::min<std::size_t>(n, 1 << 16))
        if (!decode_group()) break;
      if (pending_.empty())
        throw InputError(path_ + ": truncated base64 data (" + std::string(what) + ")");
    }
    const std::size_t take = std::min(n, pending_.size() - pending_at_);
    out.append(pending_, pending_at_, take);
    pending_at_ += take;
    n -= take;
  }
}

void zlib_inflate(const char* src, std::size_t size, std::size_t expected, std::string& out,
                  const std::string& path, std::string_view what) {
  // libdeflate straight into `out` when the stream is clean; `expected` is
  // within ~1032:1 of `size` (the callers check), so a lie costs little.
  const std::size_t start = out.size();
  out.resize(start + expected);
  if (detail::inflate_zlib_exact(src, size, out.data() + start, expected)) return;
  out.resize(start);
  // Otherwise zlib decides, streamed through a fixed buffer: `out` grows
  // only by what the data really inflates to, and inflation stops as soon as
  // the stream would exceed `expected`.
  auto fail = [&](const std::string& why) {
    return InputError(path + ": corrupt zlib data in " + std::string(what) + " (" + why + ")");
  };
  z_stream z{};
  if (inflateInit(&z) != Z_OK) throw fail("zlib cannot start");
  char buffer[1 << 16];
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(src));
  std::size_t fed = 0;
  int rc = Z_OK;
  while (rc != Z_STREAM_END) {
    if (z.avail_in == 0 && fed < size) {
      const std::size_t n = std::min<std::size_t>(size - fed, 1u << 30);
      z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(src + fed));
      z.avail_in = static_cast<uInt>(n);
      fed += n;
    }
    z.next_out = reinterpret_cast<Bytef*>(buffer);
    z.avail_out = sizeof buffer;
    rc = inflate(&z, Z_NO_FLUSH);
    const std::size_t got = sizeof buffer - z.avail_out;
    if (rc != Z_OK && rc != Z_STREAM_END && !(rc == Z_BUF_ERROR && got > 0)) {
      inflateEnd(&z);
      throw fail(rc == Z_BUF_ERROR ? "the stream ends after " + std::to_string(out.size() - start) + " of " +
                                         std::to_string(expected) + " bytes"
                                   : "zlib code " + std::to_string(rc));
    }
    if (got > expected - (out.size() - start)) {
      inflateEnd(&z);
      throw fail("inflates to more than the " + std::to_string(expected) + " bytes declared");
    }
    out.append(buffer, got);
  }
  inflateEnd(&z);
  if (out.size() - start != expected)
    throw fail("inflates to " + std::to_string(out.size() - start) + " of the " + std::to_string(expected) +
               " bytes declared");
}

void validate_mesh(const SurfaceMesh& mesh, const std::string& path) {
  if (mesh.points.size() % 3 != 0)
    throw InputError(path + ": mesh has " + std::to_string(mesh.points.size()) + " point coordinates, not a multiple of 3");
  const std::uint64_t n = mesh.points.size() / 3;
  // 1e39, inf and nan all end up non-finite as float: refused by name, never
  // written on. Each check is first one pass with no exit inside, which
  // vectorises (a whole mesh is read here), then the first offender found.
  std::uint32_t non_finite = 0;
  for (const float v : mesh.points) non_finite |= (std::bit_cast<std::uint32_t>(v) & 0x7f800000u) == 0x7f800000u;
  for (std::size_t i = 0; non_finite && i < mesh.points.size(); ++i)
    if (!std::isfinite(mesh.points[i]))
      throw InputError(path + ": point " + std::to_string(i / 3) + " has a non-finite coordinate " + "xyz"[i % 3] +
                       " = " + std::to_string(mesh.points[i]));
  if (!mesh.offsets.empty()) {
    if (mesh.offsets.front() != 0 || mesh.offsets.back() != mesh.connectivity.size())
      throw InputError(path + ": mesh offsets do not span the connectivity");
    for (std::size_t c = 0; c + 1 < mesh.offsets.size(); ++c)
      if (mesh.offsets[c + 1] < mesh.offsets[c]) throw InputError(path + ": mesh offsets decrease at cell " + std::to_string(c));
  } else if (mesh.connectivity.size() % 3 != 0) {
    throw InputError(path + ": triangle connectivity size " + std::to_string(mesh.connectivity.size()) + " is not a multiple of 3");
  }
  PointIndex largest = 0;
  for (const PointIndex id : mesh.connectivity) largest = std::max(largest, id);
  for (std::size_t i = 0; !mesh.connectivity.empty() && largest >= n && i < mesh.connectivity.size(); ++i)
    if (mesh.connectivity[i] >= n)
      throw InputError(path + ": cell point id " + std::to_string(mesh.connectivity[i]) + " out of range (" +
                       std::to_string(n) + " points)");
  for (const Field& f : mesh.point_fields)
    if (f.components < 1 || f.values.size() != n * std::uint64_t(f.components))
      throw InputError(path + ": point field '" + f.name + "' has " + std::to_string(f.values.size()) +
                       " values for " + std::to_string(n) + " points x " + std::to_string(f.components) + " components");
  const std::uint64_t cells = static_cast<std::uint64_t>(mesh.num_cells());
  for (const Field& f : mesh.cell_fields)
    if (f.components < 1 || f.values.size() != cells * std::uint64_t(f.components))
      throw InputError(path + ": cell field '" + f.name + "' has " + std::to_string(f.values.size()) +
                       " values for " + std::to_string(cells) + " cells x " + std::to_string(f.components) + " components");
}

void compact_offsets(SurfaceMesh& mesh) {
  if (mesh.offsets.empty()) return;
  for (std::size_t c = 0; c + 1 < mesh.offsets.size(); ++c)
    if (mesh.offsets[c + 1] - mesh.offsets[c] != 3) return;
  mesh.offsets.clear();
}

const Field* normals_field(const SurfaceMesh& mesh) {
  const Field* f = mesh.find_point_field("Normals");
  return (f && f->components == 3) ? f : nullptr;
}

void append_float_text(std::string& out, float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  out.append(buf, r.ptr);
}

void append_uint_text(std::string& out, std::uint64_t v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  out.append(buf, r.ptr);
}

}  // namespace keymesh::io::mesh_bytes
