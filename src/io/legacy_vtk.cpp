#include "keymesh/io/legacy_vtk.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <bit>
#include <cstdio>
#include <cstring>
#include <type_traits>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "keymesh/io/mesh_bytes.hpp"

namespace keymesh::io {

using namespace mesh_bytes;

namespace {

std::string upper(std::string_view s) {
  std::string u(s);
  std::transform(u.begin(), u.end(), u.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return u;
}

bool legacy_type(std::string_view name, Scalar& s) {
  const std::string t = upper(name);
  if (t == "FLOAT") s = Scalar::Float32;
  else if (t == "DOUBLE") s = Scalar::Float64;
  else if (t == "CHAR") s = Scalar::Int8;
  else if (t == "UNSIGNED_CHAR") s = Scalar::UInt8;
  else if (t == "SHORT") s = Scalar::Int16;
  else if (t == "UNSIGNED_SHORT") s = Scalar::UInt16;
  else if (t == "INT" || t == "VTKTYPEINT32") s = Scalar::Int32;
  else if (t == "UNSIGNED_INT" || t == "VTKTYPEUINT32") s = Scalar::UInt32;
  else if (t == "LONG" || t == "VTKTYPEINT64" || t == "VTKIDTYPE") s = Scalar::Int64;
  else if (t == "UNSIGNED_LONG" || t == "VTKTYPEUINT64") s = Scalar::UInt64;
  else return false;
  return true;
}

// A cursor over the file: words and lines of the text parts, and raw
// big-endian blocks in BINARY files.
class Reader {
 public:
  Reader(std::string_view data, const std::string& path, bool binary) : d_(data), path_(path), binary_(binary) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path_ + ": legacy VTK, line " + std::to_string(line_) + ": " + what);
  }
  void skip_space() {
    while (pos_ < d_.size() && is_space(d_[pos_])) {
      if (d_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }
  bool at_end() {
    skip_space();
    return pos_ >= d_.size();
  }
  std::string_view word() {
    skip_space();
    const std::size_t b = pos_;
    while (pos_ < d_.size() && !is_space(d_[pos_])) ++pos_;
    return d_.substr(b, pos_ - b);
  }
  std::int64_t count(const char* what) {
    std::int64_t v = 0;
    const std::string_view w = word();
    if (!parse_int64(w, v) || v < 0) fail(std::string("bad ") + what + " '" + std::string(w) + "'");
    // No file holds 2^48 values; the cap keeps products with component counts from overflowing.
    if (v > (std::int64_t{1} << 48)) fail(std::string(what) + " " + std::string(w) + " is larger than any file holds");
    return v;
  }
  // A METADATA block (INFORMATION, COMPONENT_NAMES, ...) ends at an empty line.
  void skip_metadata() {
    rest_of_line();
    while (pos_ < d_.size()) {
      std::size_t e = pos_;
      while (e < d_.size() && d_[e] != '\n' && is_space(d_[e])) ++e;
      const bool blank = e >= d_.size() || d_[e] == '\n';
      rest_of_line();
      if (blank) return;
    }
  }
  void rest_of_line() {
    while (pos_ < d_.size() && d_[pos_] != '\n') ++pos_;
    if (pos_ < d_.size()) ++pos_, ++line_;
  }
  // Refuses a count the rest of the file cannot hold, before anything of
  // that size is allocated: n binary values of type s, or n text numbers
  // (each at least one digit and a separator).
  void check_count(std::int64_t n, Scalar s, const char* what) const {
    const std::uint64_t left = d_.size() - std::min(pos_, d_.size());
    const std::uint64_t room = binary_ ? left / scalar_size(s) : left / 2 + 1;
    if (n < 0 || static_cast<std::uint64_t>(n) > room)
      fail(std::string(what) + ": " + std::to_string(n) + " values declared, the file ends first");
  }
  // n values of type s, each handed to `put(i, value)`.
  template <class Put>
  void values(std::int64_t n, Scalar s, const char* what, Put&& put) {
    check_count(n, s, what);
    if (binary_) {
      rest_of_line();  // binary data starts after the keyword line
      const std::size_t size = scalar_size(s);
      check_count(n, s, what);
      for (std::int64_t i = 0; i < n; ++i) put(i, d_.data() + pos_ + std::size_t(i) * size, true);
      pos_ += std::size_t(n) * size;
      return;
    }
    for (std::int64_t i = 0; i < n; ++i) {
      const std::string_view w = word();
      if (w.empty()) fail(std::string(what) + ": the file ends after " + std::to_string(i) + " values");
      put(i, w, false);
    }
  }
  std::vector<double> doubles(std::int64_t n, Scalar s, const char* what) {
    check_count(n, s, what);
    std::vector<double> out(static_cast<std::size_t>(n));
    values(n, s, what, [&](std::int64_t i, auto src, bool) {
      if constexpr (std::is_same_v<decltype(src), std::string_view>) {
        if (!parse_double(src, out[i])) fail(std::string(what) + ": '" + std::string(src) + "' is not a number");
      } else {
        out[i] = load_as_double(src, s, true);
      }
    });
    return out;
  }
  std::vector<std::int64_t> ints(std::int64_t n, Scalar s, const char* what) {
    check_count(n, s, what);
    std::vector<std::int64_t> out(static_cast<std::size_t>(n));
    values(n, s, what, [&](std::int64_t i, auto src, bool) {
      bool ok;
      if constexpr (std::is_same_v<decltype(src), std::string_view>) ok = parse_int64(src, out[i]);
      else ok = load_as_int64(src, s, true, out[i]);
      if (!ok) fail(std::string(what) + ": value " + std::to_string(i) + " is not an integer");
    });
    return out;
  }

 private:
  std::string_view d_;
  const std::string& path_;
  bool binary_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;

 public:
  std::size_t& pos() { return pos_; }
  std::size_t& line() { return line_; }
};

std::string unescape_name(std::string_view n) {
  std::string out;
  for (std::size_t i = 0; i < n.size(); ++i) {
    if (n[i] == '%' && i + 2 < n.size() && std::isxdigit(static_cast<unsigned char>(n[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(n[i + 2]))) {
      out.push_back(static_cast<char>(std::stoi(std::string(n.substr(i + 1, 2)), nullptr, 16)));
      i += 2;
    } else {
      out.push_back(n[i]);
    }
  }
  return out;
}

// Reads the attribute arrays of one POINT_DATA or CELL_DATA section into
// `fields` until the next section keyword (returned, "" at the end).
std::string read_attributes(Reader& r, std::int64_t tuples, std::vector<Field>& fields) {
  while (!r.at_end()) {
    const std::string key = upper(r.word());
    if (key == "POINT_DATA" || key == "CELL_DATA") return key;
    if (key == "METADATA") {
      r.skip_metadata();
      continue;
    }
    if (key == "SCALARS" || key == "VECTORS" || key == "NORMALS" || key == "TEXTURE_COORDINATES" ||
        key == "TENSORS" || key == "COLOR_SCALARS") {
      const std::string name = unescape_name(r.word());
      int comps = key == "SCALARS" ? 1 : (key == "TENSORS" ? 9 : 3);
      Scalar s = Scalar::Float32;
      if (key == "COLOR_SCALARS") {
        comps = static_cast<int>(r.count("component count"));
        s = Scalar::UInt8;  // BINARY color scalars are unsigned chars; ASCII are floats in [0, 1]
      } else {
        const std::string_view t = r.word();
        if (!legacy_type(t, s)) r.fail("unknown data type '" + std::string(t) + "' of " + name);
        if (key == "TEXTURE_COORDINATES") comps = static_cast<int>(r.count("component count"));
      }
      if (key == "SCALARS") {
        // Optional component count on the same line, then LOOKUP_TABLE.
        std::size_t save = r.pos(), line = r.line();
        std::string_view w = r.word();
        std::int64_t c = 0;
        if (parse_int64(w, c)) comps = static_cast<int>(c);
        else r.pos() = save, r.line() = line;
        save = r.pos(), line = r.line();
        if (upper(r.word()) == "LOOKUP_TABLE") r.word();
        else r.pos() = save, r.line() = line;
      }
      if (comps < 1 || comps > 64) r.fail("array " + name + " has " + std::to_string(comps) + " components");
      const auto v = r.doubles(tuples * comps, s, name.c_str());
      fields.push_back(Field{key == "NORMALS" ? std::string("Normals") : name, comps,
                             std::vector<float>(v.begin(), v.end())});
      continue;
    }
    if (key == "LOOKUP_TABLE") {  // a table of colours given in the data section
      r.word();
      const std::int64_t n = r.count("lookup table size");
      r.doubles(4 * n, Scalar::UInt8, "LOOKUP_TABLE");
      continue;
    }
    if (key == "FIELD") {
      r.word();
      const std::int64_t arrays = r.count("FIELD array count");
      for (std::int64_t a = 0; a < arrays; ++a) {
        const std::string name = unescape_name(r.word());
        const std::int64_t comps = r.count("component count");
        const std::int64_t n = r.count("tuple count");
        Scalar s;
        const std::string_view t = r.word();
        if (!legacy_type(t, s)) r.fail("unknown data type '" + std::string(t) + "' of FIELD array " + name);
        if (comps < 1 || comps > 64) r.fail("FIELD array " + name + " has " + std::to_string(comps) + " components");
        const auto v = r.doubles(n * comps, s, name.c_str());
        if (n == tuples) fields.push_back(Field{name, int(comps), std::vector<float>(v.begin(), v.end())});
      }
      continue;
    }
    r.fail("unexpected keyword '" + key + "'");
  }
  return "";
}

}  // namespace

std::string legacy_vtk_dataset(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!std::getline(in, line) || line.rfind("# vtk DataFile", 0) != 0) return "";
  for (int i = 0; i < 3 && std::getline(in, line); ++i) {
    const std::string u = upper(line);
    if (u.rfind("DATASET", 0) == 0) {
      std::string t = u.substr(7);
      t.erase(0, t.find_first_not_of(" \t"));
      t.erase(t.find_last_not_of(" \t\r") + 1);
      return t;
    }
  }
  return "";
}

UnstructuredGrid read_legacy_vtk(const std::string& path) { return parse_legacy_vtk(read_whole_file(path), path); }

UnstructuredGrid parse_legacy_vtk(std::string_view data, const std::string& path) {
  // Header: magic line, title line, ASCII|BINARY, DATASET type.
  std::size_t p = 0;
  auto line = [&]() {
    const std::size_t e = data.find('\n', p);
    std::string_view l = data.substr(p, e == std::string_view::npos ? std::string_view::npos : e - p);
    p = e == std::string_view::npos ? data.size() : e + 1;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    return l;
  };
  if (line().rfind("# vtk DataFile", 0) != 0) throw InputError(path + ": not a legacy VTK file (no '# vtk DataFile' line)");
  line();  // title
  const std::string mode = upper(line());
  const bool binary = mode.rfind("BINARY", 0) == 0;
  if (!binary && mode.rfind("ASCII", 0) != 0) throw InputError(path + ": legacy VTK format is '" + mode + "', not ASCII or BINARY");
  Reader r(data.substr(p), path, binary);
  r.line() = 4;
  if (upper(r.word()) != "DATASET") r.fail("expected DATASET");
  const std::string dataset = upper(r.word());
  if (dataset != "UNSTRUCTURED_GRID")
    r.fail("dataset is " + dataset + ", not UNSTRUCTURED_GRID (keymesh reads unstructured grids from .vtk)");

  UnstructuredGrid g;
  std::int64_t npts = -1, ncells = -1;
  std::vector<std::int64_t> ids, offsets;
  std::vector<std::int64_t> types;
  std::string next;
  while (!r.at_end() || !next.empty()) {
    const std::string key = next.empty() ? upper(r.word()) : next;
    next.clear();
    if (key == "POINTS") {
      npts = r.count("point count");
      Scalar s;
      const std::string_view t = r.word();
      if (!legacy_type(t, s)) r.fail("unknown point type '" + std::string(t) + "'");
      const auto v = r.doubles(3 * npts, s, "POINTS");
      g.points.assign(v.begin(), v.end());
    } else if (key == "CELLS") {
      const std::int64_t a = r.count("cell count"), b = r.count("CELLS size");
      // 5.x: "CELLS offsets_count connectivity_count" then OFFSETS and CONNECTIVITY arrays.
      const std::size_t save = r.pos(), save_line = r.line();
      if (upper(r.word()) == "OFFSETS") {
        Scalar s;
        if (!legacy_type(r.word(), s)) r.fail("bad OFFSETS type");
        offsets = r.ints(a, s, "OFFSETS");
        if (upper(r.word()) != "CONNECTIVITY") r.fail("expected CONNECTIVITY after OFFSETS");
        if (!legacy_type(r.word(), s)) r.fail("bad CONNECTIVITY type");
        ids = r.ints(b, s, "CONNECTIVITY");
        ncells = a > 0 ? a - 1 : 0;
      } else {
        r.pos() = save, r.line() = save_line;
        ncells = a;
        const auto raw = r.ints(b, Scalar::Int32, "CELLS");
        offsets.assign(1, 0);
        std::size_t at = 0;
        for (std::int64_t c = 0; c < ncells; ++c) {
          if (at >= raw.size() || raw[at] < 0 || std::uint64_t(raw[at]) > raw.size() - at - 1)
            r.fail("CELLS list is inconsistent at cell " + std::to_string(c));
          ids.insert(ids.end(), raw.begin() + std::ptrdiff_t(at + 1), raw.begin() + std::ptrdiff_t(at + 1 + raw[at]));
          at += std::size_t(raw[at]) + 1;
          offsets.push_back(std::int64_t(ids.size()));
        }
        if (at != raw.size()) r.fail("CELLS size " + std::to_string(b) + " does not match the cells listed");
      }
    } else if (key == "CELL_TYPES") {
      const std::int64_t n = r.count("cell type count");
      types = r.ints(n, Scalar::Int32, "CELL_TYPES");
    } else if (key == "POINT_DATA" || key == "CELL_DATA") {
      const std::int64_t n = r.count("tuple count");
      next = read_attributes(r, n, key == "POINT_DATA" ? g.point_fields : g.cell_fields);
    } else if (key == "METADATA" || key == "FIELD") {
      std::vector<Field> ignored;  // dataset-level field data is not kept
      next = key == "FIELD" ? (r.pos() -= 5, read_attributes(r, -1, ignored)) : (r.skip_metadata(), std::string());
    } else {
      r.fail("unexpected keyword '" + key + "'");
    }
  }
  if (npts < 0) throw InputError(path + ": legacy VTK file has no POINTS");
  if (ncells < 0) ncells = 0;
  if (std::int64_t(types.size()) != ncells)
    throw InputError(path + ": " + std::to_string(types.size()) + " CELL_TYPES for " + std::to_string(ncells) + " cells");
  if (offsets.empty()) offsets.assign(1, 0);
  if (std::int64_t(offsets.size()) != ncells + 1 || offsets.front() != 0 || offsets.back() != std::int64_t(ids.size()))
    throw InputError(path + ": cell offsets do not match the connectivity");
  g.connectivity = IndexArray::for_ids(std::uint64_t(npts), ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) {
    if (ids[k] < 0 || ids[k] >= npts)
      throw InputError(path + ": cell connectivity refers to point " + std::to_string(ids[k]) + " out of range (" +
                       std::to_string(npts) + " points)");
    g.connectivity.set(k, std::uint64_t(ids[k]));
  }
  g.offsets.assign(offsets.begin(), offsets.end());
  g.cell_types.resize(types.size());
  for (std::size_t c = 0; c < types.size(); ++c) {
    if (types[c] < 0 || types[c] > 255) throw InputError(path + ": cell " + std::to_string(c) + " has type " + std::to_string(types[c]));
    g.cell_types[c] = static_cast<std::uint8_t>(types[c]);
  }
  // One fixed-size type throughout: store it uniformly.
  if (!g.cell_types.empty() && std::all_of(g.cell_types.begin(), g.cell_types.end(), [&](std::uint8_t t) { return t == g.cell_types[0]; })) {
    const int k = cell_type_size(static_cast<CellType>(g.cell_types[0]));
    bool uniform = k > 0;
    for (std::size_t c = 0; uniform && c + 1 < g.offsets.size(); ++c) uniform = g.offsets[c + 1] - g.offsets[c] == std::uint64_t(k);
    if (uniform) {
      g.uniform_type = static_cast<CellType>(g.cell_types[0]);
      g.offsets.clear();
      g.cell_types.clear();
    }
  } else if (g.cell_types.empty()) {
    g.offsets.clear();
  }
  for (auto* fields : {&g.point_fields, &g.cell_fields})
    for (const Field& f : *fields)
      if (f.components < 1) throw InputError(path + ": array " + f.name + " is empty");
  g.validate(path);
  return g;
}

void write_legacy_vtk(const UnstructuredGrid& g, const std::string& path) {
  g.validate(path);
  const Id n = g.num_points(), cells = g.num_cells();
  const std::uint64_t cells_size = g.connectivity.size() + std::uint64_t(cells);
  if (std::uint64_t(n) > std::uint64_t(std::numeric_limits<std::int32_t>::max()) ||
      cells_size > std::uint64_t(std::numeric_limits<std::int32_t>::max()))
    throw LimitError(path + ": legacy .vtk holds 32-bit ids and sizes; " + std::to_string(cells_size) +
                     " cell entries do not fit (write .vtu instead)");
  AtomicFile file(path);
  std::string buf;
  auto flush = [&](bool force) {
    if (force || buf.size() >= (1 << 20)) {
      file.write(buf);
      buf.clear();
    }
  };
  auto be32 = [&](std::uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) buf.push_back(static_cast<char>((v >> s) & 0xff));
    flush(false);
  };
  auto be_float = [&](float f) { be32(std::bit_cast<std::uint32_t>(f)); };
  auto name_of = [](const std::string& s) {
    std::string out;
    for (char c : s) {
      if (c == ' ' || c == '%' || c == '\t' || c == '\n') {
        char hex[4];
        std::snprintf(hex, sizeof hex, "%%%02X", static_cast<unsigned char>(c));
        out += hex;
      } else {
        out.push_back(c);
      }
    }
    return out.empty() ? std::string("array") : out;
  };
  buf += "# vtk DataFile Version 4.2\nkeymesh\nBINARY\nDATASET UNSTRUCTURED_GRID\n";
  buf += "POINTS " + std::to_string(n) + " float\n";
  for (float x : g.points) be_float(x);
  buf += "\nCELLS " + std::to_string(cells) + " " + std::to_string(cells_size) + "\n";
  for (Id c = 0; c < cells; ++c) {
    be32(static_cast<std::uint32_t>(g.cell_end(c) - g.cell_begin(c)));
    for (std::uint64_t k = g.cell_begin(c); k < g.cell_end(c); ++k) be32(static_cast<std::uint32_t>(g.connectivity[k]));
  }
  buf += "\nCELL_TYPES " + std::to_string(cells) + "\n";
  for (Id c = 0; c < cells; ++c) be32(g.cell_type(c));
  buf += "\n";
  auto section = [&](const char* tag, const std::vector<Field>& fields, Id tuples) {
    if (fields.empty()) return;
    buf += std::string(tag) + " " + std::to_string(tuples) + "\n";
    for (const Field& f : fields) {
      if (f.components == 1) buf += "SCALARS " + name_of(f.name) + " float 1\nLOOKUP_TABLE default\n";
      else if (f.components == 3 && f.name == "Normals") buf += "NORMALS Normals float\n";
      else if (f.components == 3) buf += "VECTORS " + name_of(f.name) + " float\n";
      else buf += "FIELD FieldData 1\n" + name_of(f.name) + " " + std::to_string(f.components) + " " + std::to_string(tuples) + " float\n";
      for (float x : f.values) be_float(x);
      buf += "\n";
    }
  };
  section("POINT_DATA", g.point_fields, n);
  section("CELL_DATA", g.cell_fields, cells);
  flush(true);
  file.commit();
}

}  // namespace keymesh::io
