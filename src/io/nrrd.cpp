// NRRD (teem's "nearly raw raster data"): a text header, then raw or gzip
// samples, attached (.nrrd) or in a separate file (.nhdr "data file:").
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <vector>

#include "keymesh/io/atomic_file.hpp"
#include "keymesh/io/input_file.hpp"
#include "volume_formats.hpp"
#include "whole_inflate.hpp"

namespace keymesh::io {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

ScalarType nrrd_type(const std::string& path, const std::string& raw) {
  const std::string t = lower(raw);
  if (t == "signed char" || t == "int8" || t == "int8_t") return ScalarType::Int8;
  if (t == "uchar" || t == "unsigned char" || t == "uint8" || t == "uint8_t") return ScalarType::UInt8;
  if (t == "short" || t == "short int" || t == "signed short" || t == "signed short int" || t == "int16" ||
      t == "int16_t")
    return ScalarType::Int16;
  if (t == "ushort" || t == "unsigned short" || t == "unsigned short int" || t == "uint16" || t == "uint16_t")
    return ScalarType::UInt16;
  if (t == "int" || t == "signed int" || t == "int32" || t == "int32_t") return ScalarType::Int32;
  if (t == "uint" || t == "unsigned int" || t == "uint32" || t == "uint32_t") return ScalarType::UInt32;
  if (t == "longlong" || t == "long long" || t == "long long int" || t == "signed long long" ||
      t == "signed long long int" || t == "int64" || t == "int64_t")
    return ScalarType::Int64;
  if (t == "ulonglong" || t == "unsigned long long" || t == "unsigned long long int" || t == "uint64" ||
      t == "uint64_t")
    return ScalarType::UInt64;
  if (t == "float") return ScalarType::Float32;
  if (t == "double") return ScalarType::Float64;
  throw InputError(path + ": NRRD type '" + raw +
                   "' is not supported (int8, uint8, int16, uint16, int32, uint32, int64, uint64, float, double)");
}

std::vector<std::string> words(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

double parse_number(const std::string& path, const std::string& field, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(v))
    throw InputError(path + ": NRRD field '" + field + "' has a bad number '" + text + "'");
  return v;
}

// Parses "(x,y,z)" vectors of a "space directions"/"space origin" field.
std::vector<std::vector<double>> vectors(const std::string& path, const std::string& field, const std::string& text) {
  std::vector<std::vector<double>> out;
  std::size_t pos = 0;
  while ((pos = text.find_first_not_of(" \t", pos)) != std::string::npos) {
    if (text.compare(pos, 4, "none") == 0) {
      out.push_back({});
      pos += 4;
      continue;
    }
    if (text[pos] != '(') throw InputError(path + ": NRRD field '" + field + "' is malformed");
    const auto close = text.find(')', pos);
    if (close == std::string::npos) throw InputError(path + ": NRRD field '" + field + "' is malformed");
    std::vector<double> v;
    std::stringstream in(text.substr(pos + 1, close - pos - 1));
    for (std::string c; std::getline(in, c, ',');) v.push_back(parse_number(path, field, trim(c)));
    out.push_back(v);
    pos = close + 1;
  }
  return out;
}

// Reads `size` bytes of gzip data from `path` at `offset` (and no more):
// with libdeflate when the data is clean, otherwise zlib decides.
Array<std::byte> read_gzip(const std::string& path, std::uint64_t offset, std::uint64_t file_bytes,
                                 std::uint64_t size) {
  if (auto samples = detail::inflate_gzip_file(path, offset, 0, size)) return std::move(*samples);
  InputFile in(path);
  if (fseeko(in.stream(), static_cast<off_t>(offset), SEEK_SET) != 0)
    throw InputError(path + ": cannot seek to the data");
  const int fd = dup(fileno(in.stream()));
  gzFile gz = fd >= 0 ? gzdopen(fd, "rb") : nullptr;
  if (!gz) {
    if (fd >= 0) close(fd);
    throw InputError(path + ": cannot open gzip data");
  }
  try {
    auto out = detail::read_gz_growing(gz, size, file_bytes - std::min(file_bytes, offset), path, "NRRD gzip data",
                                       false);
    gzclose(gz);
    return out;
  } catch (...) {
    gzclose(gz);
    throw;
  }
}

// The header's fields by lower-case name, and the bytes of header text (where
// attached samples start).
struct NrrdHeader {
  std::map<std::string, std::string> field;
  std::uint64_t bytes = 0;

  const std::string* get(const std::string& k) const {
    const auto it = field.find(k);
    return it == field.end() ? nullptr : &it->second;
  }
  // A field teem spells two ways ("data file" / "datafile").
  const std::string* get(const std::string& k, const std::string& other) const {
    const std::string* v = get(k);
    return v ? v : get(other);
  }
  void set(const std::string& line, std::size_t colon) {
    field[lower(trim(line.substr(0, colon)))] = trim(line.substr(colon + 1));
  }
};

// One header line (without its newline); returns the character that ended
// it, '\n' or EOF.
int read_header_line(std::FILE* f, std::string& line, const std::string& path) {
  line.clear();
  int c;
  while ((c = std::fgetc(f)) != EOF && c != '\n') {
    line.push_back(static_cast<char>(c));
    if (line.size() > 65536) throw InputError(path + ": NRRD header line too long");
  }
  return c;
}

// The header: text lines up to an empty line (or the end of a .nhdr).
NrrdHeader read_header(std::FILE* f, const std::string& path) {
  NrrdHeader h;
  std::string line;
  bool first = true;
  while (true) {
    const int c = read_header_line(f, line, path);
    h.bytes += line.size() + (c == '\n' ? 1 : 0);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (first) {
      first = false;
      if (line.rfind("NRRD000", 0) != 0) throw InputError(path + ": not a NRRD file (no NRRD000x magic)");
      continue;
    }
    if (line.empty() || c == EOF) {
      if (!line.empty() && line[0] != '#') {
        const auto colon = line.find(':');
        if (colon != std::string::npos) h.set(line, colon);
      }
      return h;
    }
    if (line[0] == '#') continue;
    const auto sep = line.find(":=");  // key/value pairs: ignored
    if (sep != std::string::npos && line.find(": ") == std::string::npos) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) throw InputError(path + ": malformed NRRD header line '" + line.substr(0, 60) + "'");
    h.set(line, colon);
  }
}

// The sizes of every axis, and which three are the volume's.
struct NrrdAxes {
  std::vector<Id> sizes;
  int first = 0;  // 1 when a leading 1-sample axis (e.g. one component) comes first
  std::array<Id, 3> dims{};
};

NrrdAxes parse_axes(const std::string& dimension, const std::string& sizes, const std::string& path) {
  const auto size_words = words(sizes);
  const double dim_value = parse_number(path, "dimension", dimension);
  if (dim_value != static_cast<double>(size_words.size()))
    throw InputError(path + ": NRRD dimension " + dimension + " but " + std::to_string(size_words.size()) + " sizes");
  NrrdAxes axes;
  for (const auto& w : size_words) {
    const double v = parse_number(path, "sizes", w);
    if (v < 1 || v != std::floor(v) || v > 9.0e15) throw InputError(path + ": NRRD size '" + w + "' is not a positive integer");
    axes.sizes.push_back(static_cast<Id>(v));
  }
  const auto& sz = axes.sizes;
  if (sz.size() == 4 && sz[0] == 1) axes.first = 1;
  else if (sz.size() != 3)
    throw InputError(path + ": NRRD dimension " + std::to_string(sz.size()) + " (only 3D scalar volumes)");
  axes.dims = {sz[axes.first], sz[axes.first + 1], sz[axes.first + 2]};
  return axes;
}

// "raw" or "gzip".
std::string parse_encoding(const NrrdHeader& h, const std::string& path) {
  std::string encoding = "raw";
  if (const std::string* e = h.get("encoding")) encoding = lower(*e);
  if (encoding == "gz") encoding = "gzip";
  if (encoding != "raw" && encoding != "gzip")
    throw InputError(path + ": NRRD encoding '" + encoding + "' is not supported (raw, gzip)");
  return encoding;
}

// Spacing from "spacings" or the lengths of the "space directions", origin
// from "space origin", into the layout.
void parse_geometry(const NrrdHeader& h, const NrrdAxes& axes, RawOptions& raw, const std::string& path) {
  std::array<double, 3>& spacing = raw.spacing;
  spacing = {1, 1, 1};
  raw.origin = {0, 0, 0};
  if (const std::string* sp = h.get("spacings")) {
    const auto w = words(*sp);
    if (w.size() != axes.sizes.size())
      throw InputError(path + ": NRRD spacings has " + std::to_string(w.size()) + " entries");
    for (int a = 0; a < 3; ++a) {
      if (lower(w[axes.first + a]) == "nan") continue;
      spacing[a] = std::abs(parse_number(path, "spacings", w[axes.first + a]));
    }
  } else if (const std::string* sd = h.get("space directions")) {
    const auto v = vectors(path, "space directions", *sd);
    if (v.size() != axes.sizes.size())
      throw InputError(path + ": NRRD space directions has " + std::to_string(v.size()) + " entries");
    for (int a = 0; a < 3; ++a) {
      double len2 = 0;
      for (double x : v[axes.first + a]) len2 += x * x;
      if (len2 > 0) spacing[a] = std::sqrt(len2);
    }
  }
  if (const std::string* so = h.get("space origin")) {
    const auto v = vectors(path, "space origin", *so);
    if (v.size() == 1 && v[0].size() == 3) raw.origin = {v[0][0], v[0][1], v[0][2]};
  }
  for (int a = 0; a < 3; ++a)
    if (!(spacing[a] > 0)) throw InputError(path + ": NRRD spacing along axis " + std::to_string(a) + " is not positive");
}

// The file holding the samples: the header's own, or its "data file".
std::string data_file_path(const std::string* data_file, const std::string& path) {
  if (!data_file) return path;
  if (data_file->rfind("LIST", 0) == 0 || data_file->find('%') != std::string::npos)
    throw InputError(path + ": NRRD multi-file data is not supported");
  std::filesystem::path p(*data_file);
  if (p.is_relative()) p = std::filesystem::path(path).parent_path() / p;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(p.string(), ec))
    throw InputError(path + ": NRRD data file '" + p.string() + "' is not a readable file");
  return p.string();
}

// Where the samples start in `data_path` after the skips: whole lines, then
// bytes. With gzip, teem applies them to the decompressed stream: not
// supported (a silent offset would read garbage).
std::uint64_t skip_to_samples(const NrrdHeader& h, const std::string& encoding, const std::string& data_path,
                              std::uint64_t offset, const std::string& path) {
  const std::string* line_skip = h.get("line skip", "lineskip");
  const std::string* byte_skip = h.get("byte skip", "byteskip");
  if (encoding != "raw" && ((line_skip && parse_number(path, "line skip", *line_skip) != 0) ||
                            (byte_skip && parse_number(path, "byte skip", *byte_skip) != 0)))
    throw InputError(path + ": NRRD line skip / byte skip with " + encoding + " encoding is not supported");
  if (line_skip) {
    const double v = parse_number(path, "line skip", *line_skip);
    if (v < 0 || v != std::floor(v) || v > 1e12) throw InputError(path + ": NRRD line skip " + *line_skip + " is not supported");
    InputFile data_in(data_path);
    std::FILE* d = data_in.stream();
    if (fseeko(d, static_cast<off_t>(offset), SEEK_SET) != 0)
      throw InputError(path + ": cannot read the NRRD data file '" + data_path + "'");
    for (double lines = 0; lines < v;) {
      const int c = std::fgetc(d);
      if (c == EOF) throw InputError(path + ": NRRD line skip " + *line_skip + " passes the end of '" + data_path + "'");
      ++offset;
      if (c == '\n') ++lines;
    }
  }
  if (byte_skip) {
    const double v = parse_number(path, "byte skip", *byte_skip);
    if (v < 0 || v != std::floor(v) || v > 9.0e15)
      throw InputError(path + ": NRRD byte skip " + *byte_skip + " is not supported");
    offset += static_cast<std::uint64_t>(v);
  }
  return offset;
}

}  // namespace

VolumeLayout nrrd_layout(const std::string& path) {
  InputFile header_file(path);
  const std::uint64_t file_bytes = header_file.size();
  const NrrdHeader h = read_header(header_file.stream(), path);
  const std::string* type = h.get("type");
  const std::string* dimension = h.get("dimension");
  const std::string* sizes = h.get("sizes");
  if (!type || !dimension || !sizes) throw InputError(path + ": NRRD header lacks type, dimension or sizes");
  VolumeLayout layout;
  layout.raw.type = nrrd_type(path, *type);
  const NrrdAxes axes = parse_axes(*dimension, *sizes, path);
  layout.raw.dims = axes.dims;
  if (const std::string* e = h.get("endian")) {
    if (lower(*e) == "big") layout.raw.big_endian = true;
    else if (lower(*e) != "little") throw InputError(path + ": NRRD endian '" + *e + "'");
  }
  const std::string encoding = parse_encoding(h, path);
  parse_geometry(h, axes, layout.raw, path);
  const std::string* data_file = h.get("data file", "datafile");
  const std::string data_path = data_file_path(data_file, path);
  const std::uint64_t data_offset = skip_to_samples(h, encoding, data_path, data_file ? 0 : h.bytes, path);
  // Refuse a body shorter than declared before allocating.
  const std::uint64_t data_file_bytes = data_file ? detail::file_size_or_throw(data_path) : file_bytes;
  const std::uint64_t need = detail::checked_byte_count(axes.dims, layout.raw.type, path);
  const std::uint64_t body = data_file_bytes - std::min(data_file_bytes, data_offset);
  if (encoding == "raw" && need > body)
    throw InputError(data_path + ": NRRD data holds " + std::to_string(body) + " bytes, the header of " + path +
                     " declares " + std::to_string(need) + " (sizes " + *sizes + ", type " + *type + ")");
  // zlib cannot expand more than ~1032:1.
  if (encoding == "gzip" && need / 1032 > body + 64)
    throw InputError(data_path + ": NRRD gzip data of " + std::to_string(body) + " bytes cannot hold the " +
                     std::to_string(need) + " bytes the header of " + path + " declares (sizes " + *sizes + ")");
  layout.data_path = data_path;
  layout.raw.header_bytes = static_cast<Id>(data_offset);
  if (encoding != "raw") layout.compressed = encoding;
  return layout;
}

ImageGrid read_nrrd(const std::string& path) {
  const VolumeLayout layout = nrrd_layout(path);
  ImageGrid grid;
  grid.name = layout.name;
  grid.spacing = layout.raw.spacing;
  grid.origin = layout.raw.origin;
  const auto offset = static_cast<std::uint64_t>(layout.raw.header_bytes);
  if (layout.compressed.empty()) {
    detail::allocate_checked(grid, layout.raw.dims, layout.raw.type, path);
    detail::read_exact(layout.data_path, offset, grid.data(), grid.bytes.size(), "the samples");
  } else {
    const std::uint64_t need = detail::checked_byte_count(layout.raw.dims, layout.raw.type, path);
    detail::adopt_samples(grid, layout.raw.dims, layout.raw.type,
                          read_gzip(layout.data_path, offset, detail::file_size_or_throw(layout.data_path), need));
  }
  if (layout.raw.big_endian) detail::swap_samples(grid);
  return grid;
}

void write_nrrd(const ImageGrid& grid, const std::string& path) {
  // NRRD's names are ours except for the two float types.
  const char* type = grid.type == ScalarType::Float32   ? "float"
                     : grid.type == ScalarType::Float64 ? "double"
                                                        : scalar_type_name(grid.type);
  char header[1024];
  std::snprintf(header, sizeof header,
                "NRRD0004\n# written by keymesh\ntype: %s\ndimension: 3\nsizes: %lld %lld %lld\n"
                "space dimension: 3\nspace directions: (%.17g,0,0) (0,%.17g,0) (0,0,%.17g)\n"
                "space origin: (%.17g,%.17g,%.17g)\nendian: little\nencoding: raw\n\n",
                type, static_cast<long long>(grid.dims[0]), static_cast<long long>(grid.dims[1]),
                static_cast<long long>(grid.dims[2]), grid.spacing[0], grid.spacing[1], grid.spacing[2],
                grid.origin[0], grid.origin[1], grid.origin[2]);
  AtomicFile f(path);
  f.write(std::string_view(header));
  f.write(grid.data(), grid.bytes.size());
  f.commit();
}

}  // namespace keymesh::io
