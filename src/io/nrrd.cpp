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
#include "keymesh/io/volume_formats.hpp"

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
  if (t == "float") return ScalarType::Float32;
  if (t == "double") return ScalarType::Float64;
  throw InputError(path + ": NRRD type '" + raw +
                   "' is not supported (int8, uint8, int16, uint16, int32, float, double)");
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

// Reads `size` bytes of gzip data from `path` at `offset` (and no more).
std::vector<std::byte> read_gzip(const std::string& path, std::uint64_t offset, std::uint64_t file_bytes,
                                 std::uint64_t size) {
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

}  // namespace

VolumeLayout nrrd_layout(const std::string& path) {
  InputFile header_file(path);
  const std::uint64_t file_bytes = header_file.size();
  std::FILE* f = header_file.stream();
  // The header: text lines up to an empty line (or the end of a .nhdr).
  std::string magic_line;
  std::map<std::string, std::string> field;
  std::uint64_t data_offset = 0;
  {
    std::string line;
    int c;
    bool first = true;
    std::uint64_t consumed = 0;
    while (true) {
      line.clear();
      while ((c = std::fgetc(f)) != EOF && c != '\n') {
        line.push_back(static_cast<char>(c));
        if (line.size() > 65536) {
          throw InputError(path + ": NRRD header line too long");
        }
      }
      consumed += line.size() + (c == '\n' ? 1 : 0);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (first) {
        first = false;
        if (line.rfind("NRRD000", 0) != 0) {
          throw InputError(path + ": not a NRRD file (no NRRD000x magic)");
        }
        magic_line = line;
        continue;
      }
      if (line.empty() || c == EOF) {
        if (!line.empty() && line[0] != '#') {
          const auto colon = line.find(':');
          if (colon != std::string::npos) field[lower(trim(line.substr(0, colon)))] = trim(line.substr(colon + 1));
        }
        break;
      }
      if (line[0] == '#') continue;
      const auto sep = line.find(":=");  // key/value pairs: ignored
      if (sep != std::string::npos && line.find(": ") == std::string::npos) continue;
      const auto colon = line.find(':');
      if (colon == std::string::npos) {
        throw InputError(path + ": malformed NRRD header line '" + line.substr(0, 60) + "'");
      }
      field[lower(trim(line.substr(0, colon)))] = trim(line.substr(colon + 1));
    }
    data_offset = consumed;
  }
  auto get = [&](const std::string& k) -> const std::string* {
    const auto it = field.find(k);
    return it == field.end() ? nullptr : &it->second;
  };
  const std::string* type = get("type");
  const std::string* dimension = get("dimension");
  const std::string* sizes = get("sizes");
  if (!type || !dimension || !sizes) throw InputError(path + ": NRRD header lacks type, dimension or sizes");
  const ScalarType st = nrrd_type(path, *type);
  const auto size_words = words(*sizes);
  const double dim_value = parse_number(path, "dimension", *dimension);
  if (dim_value != static_cast<double>(size_words.size()))
    throw InputError(path + ": NRRD dimension " + *dimension + " but " + std::to_string(size_words.size()) + " sizes");
  std::vector<Id> sz;
  for (const auto& w : size_words) {
    const double v = parse_number(path, "sizes", w);
    if (v < 1 || v != std::floor(v) || v > 9.0e15) throw InputError(path + ": NRRD size '" + w + "' is not a positive integer");
    sz.push_back(static_cast<Id>(v));
  }
  int first_axis = 0;
  if (sz.size() == 4 && sz[0] == 1) first_axis = 1;  // a leading 1-sample axis (e.g. one component)
  else if (sz.size() != 3)
    throw InputError(path + ": NRRD dimension " + std::to_string(sz.size()) + " (only 3D scalar volumes)");
  const std::array<Id, 3> dims{sz[first_axis], sz[first_axis + 1], sz[first_axis + 2]};
  bool big_endian = false;
  if (const std::string* e = get("endian")) {
    if (lower(*e) == "big") big_endian = true;
    else if (lower(*e) != "little") throw InputError(path + ": NRRD endian '" + *e + "'");
  }
  std::string encoding = "raw";
  if (const std::string* e = get("encoding")) encoding = lower(*e);
  if (encoding == "gz") encoding = "gzip";
  if (encoding != "raw" && encoding != "gzip")
    throw InputError(path + ": NRRD encoding '" + encoding + "' is not supported (raw, gzip)");
  std::array<double, 3> spacing{1, 1, 1}, origin{0, 0, 0};
  if (const std::string* sp = get("spacings")) {
    const auto w = words(*sp);
    if (w.size() != sz.size()) throw InputError(path + ": NRRD spacings has " + std::to_string(w.size()) + " entries");
    for (int a = 0; a < 3; ++a) {
      if (lower(w[first_axis + a]) == "nan") continue;
      spacing[a] = std::abs(parse_number(path, "spacings", w[first_axis + a]));
    }
  } else if (const std::string* sd = get("space directions")) {
    const auto v = vectors(path, "space directions", *sd);
    if (v.size() != sz.size()) throw InputError(path + ": NRRD space directions has " + std::to_string(v.size()) + " entries");
    for (int a = 0; a < 3; ++a) {
      double len2 = 0;
      for (double x : v[first_axis + a]) len2 += x * x;
      if (len2 > 0) spacing[a] = std::sqrt(len2);
    }
  }
  if (const std::string* so = get("space origin")) {
    const auto v = vectors(path, "space origin", *so);
    if (v.size() == 1 && v[0].size() == 3) origin = {v[0][0], v[0][1], v[0][2]};
  }
  for (int a = 0; a < 3; ++a)
    if (!(spacing[a] > 0)) throw InputError(path + ": NRRD spacing along axis " + std::to_string(a) + " is not positive");
  // Where the samples are.
  std::string data_path = path;
  const std::string* data_file = get("data file");
  if (!data_file) data_file = get("datafile");
  if (data_file) {
    if (data_file->rfind("LIST", 0) == 0 || data_file->find('%') != std::string::npos)
      throw InputError(path + ": NRRD multi-file data is not supported");
    std::filesystem::path p(*data_file);
    if (p.is_relative()) p = std::filesystem::path(path).parent_path() / p;
    data_path = p.string();
    data_offset = 0;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(data_path, ec))
      throw InputError(path + ": NRRD data file '" + data_path + "' is not a readable file");
  }
  // Skips before the data: whole lines, then bytes, in the data file. With
  // gzip, teem applies them to the decompressed stream: not supported (a
  // silent offset would read garbage).
  const std::string* line_skip = get("line skip");
  if (!line_skip) line_skip = get("lineskip");
  const std::string* byte_skip = get("byte skip");
  if (!byte_skip) byte_skip = get("byteskip");
  if (encoding != "raw" && ((line_skip && parse_number(path, "line skip", *line_skip) != 0) ||
                            (byte_skip && parse_number(path, "byte skip", *byte_skip) != 0)))
    throw InputError(path + ": NRRD line skip / byte skip with " + encoding + " encoding is not supported");
  if (line_skip) {
    const double v = parse_number(path, "line skip", *line_skip);
    if (v < 0 || v != std::floor(v) || v > 1e12) throw InputError(path + ": NRRD line skip " + *line_skip + " is not supported");
    InputFile data_in(data_path);
    std::FILE* d = data_in.stream();
    if (fseeko(d, static_cast<off_t>(data_offset), SEEK_SET) != 0)
      throw InputError(path + ": cannot read the NRRD data file '" + data_path + "'");
    for (double lines = 0; lines < v;) {
      const int c = std::fgetc(d);
      if (c == EOF) {
        throw InputError(path + ": NRRD line skip " + *line_skip + " passes the end of '" + data_path + "'");
      }
      ++data_offset;
      if (c == '\n') ++lines;
    }
  }
  if (byte_skip) {
    const double v = parse_number(path, "byte skip", *byte_skip);
    if (v < 0 || v != std::floor(v) || v > 9.0e15)
      throw InputError(path + ": NRRD byte skip " + *byte_skip + " is not supported");
    data_offset += static_cast<std::uint64_t>(v);
  }
  // Refuse a body shorter than declared before allocating.
  const std::uint64_t data_file_bytes = data_file ? detail::file_size_or_throw(data_path) : file_bytes;
  const std::uint64_t need = detail::checked_byte_count(dims, st, path);
  const std::uint64_t body = data_file_bytes - std::min(data_file_bytes, data_offset);
  if (encoding == "raw" && need > body)
    throw InputError(data_path + ": NRRD data holds " + std::to_string(body) + " bytes, the header of " + path +
                     " declares " + std::to_string(need) + " (sizes " + *sizes + ", type " + *type + ")");
  // zlib cannot expand more than ~1032:1.
  if (encoding == "gzip" && need / 1032 > body + 64)
    throw InputError(data_path + ": NRRD gzip data of " + std::to_string(body) + " bytes cannot hold the " +
                     std::to_string(need) + " bytes the header of " + path + " declares (sizes " + *sizes + ")");
  VolumeLayout layout;
  layout.data_path = data_path;
  layout.raw.dims = dims;
  layout.raw.type = st;
  layout.raw.spacing = spacing;
  layout.raw.origin = origin;
  layout.raw.big_endian = big_endian;
  layout.raw.header_bytes = static_cast<Id>(data_offset);
  if (encoding != "raw") layout.compressed = encoding;
  return layout;
}

ImageGrid read_nrrd(const std::string& path) {
  const VolumeLayout layout = nrrd_layout(path);
  ImageGrid grid;
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
