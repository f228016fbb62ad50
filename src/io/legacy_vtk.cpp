#include "mesh_formats.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "keymesh/io/input_file.hpp"
#include "mesh_bytes.hpp"

#include "type_names.hpp"

namespace keymesh::io {

using namespace mesh_bytes;

namespace {

std::string upper(std::string_view s) {
  std::string u(s);
  std::transform(u.begin(), u.end(), u.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return u;
}

// Legacy VTK's type names (upper-cased; the vtktype* names of 5.x files too).
constexpr TypeName kLegacyTypes[] = {
    {"FLOAT", ScalarType::Float32},          {"DOUBLE", ScalarType::Float64},
    {"CHAR", ScalarType::Int8},              {"UNSIGNED_CHAR", ScalarType::UInt8},
    {"SHORT", ScalarType::Int16},            {"UNSIGNED_SHORT", ScalarType::UInt16},
    {"INT", ScalarType::Int32},              {"VTKTYPEINT32", ScalarType::Int32},
    {"UNSIGNED_INT", ScalarType::UInt32},    {"VTKTYPEUINT32", ScalarType::UInt32},
    {"LONG", ScalarType::Int64},             {"VTKTYPEINT64", ScalarType::Int64},
    {"VTKIDTYPE", ScalarType::Int64},        {"UNSIGNED_LONG", ScalarType::UInt64},
    {"VTKTYPEUINT64", ScalarType::UInt64},   {"VTKTYPEINT8", ScalarType::Int8},
    {"VTKTYPEUINT8", ScalarType::UInt8},     {"VTKTYPEINT16", ScalarType::Int16},
    {"VTKTYPEUINT16", ScalarType::UInt16},   {"VTKTYPEFLOAT32", ScalarType::Float32},
    {"VTKTYPEFLOAT64", ScalarType::Float64},
};

bool legacy_type(std::string_view name, ScalarType& s) {
  const auto t = type_named(upper(name), kLegacyTypes);
  if (t) s = *t;
  return t.has_value();
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
    if (!parse_int64(w, v) || v < 0) fail(std::string("bad ") + what + " '" + std::string(w.substr(0, 40)) + "'");
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
  void check_count(std::int64_t n, ScalarType s, const std::string& what) const {
    const std::uint64_t left = d_.size() - std::min(pos_, d_.size());
    const std::uint64_t room = binary_ ? left / scalar_size(s) : left / 2 + 1;
    if (n < 0 || static_cast<std::uint64_t>(n) > room)
      fail(what + ": " + std::to_string(n) + " values declared, the file ends first");
  }
  // n values of type s, each handed to put(i, text) in ASCII files or
  // put(i, pointer to the big-endian value) in BINARY ones.
  template <class Text, class Binary>
  void values(std::int64_t n, ScalarType s, const std::string& what, Text&& text, Binary&& bin) {
    check_count(n, s, what);
    if (binary_) {
      rest_of_line();  // binary data starts after the keyword line
      check_count(n, s, what);
      const std::size_t size = scalar_size(s);
      for (std::int64_t i = 0; i < n; ++i) bin(i, d_.data() + pos_ + std::size_t(i) * size);
      pos_ += std::size_t(n) * size;
      return;
    }
    for (std::int64_t i = 0; i < n; ++i) {
      const std::string_view w = word();
      if (w.empty()) fail(what + ": the file ends after " + std::to_string(i) + " of " + std::to_string(n) + " values");
      text(i, w);
    }
  }
  // n numbers as floats.
  Array<float> floats(std::int64_t n, ScalarType s, const std::string& what) {
    check_count(n, s, what);
    Array<float> out(static_cast<std::size_t>(n));  // every value written (or the read fails)
    values(
        n, s, what,
        [&](std::int64_t i, std::string_view w) {
          double v = 0;
          if (!parse_double(w, v)) fail(what + ": '" + std::string(w.substr(0, 40)) + "' is not a number");
          out[std::size_t(i)] = static_cast<float>(v);
        },
        [&](std::int64_t i, const char* p) { out[std::size_t(i)] = static_cast<float>(load_as_double(p, s, true)); });
    return out;
  }
  // n integers, each handed to put(i, value).
  template <class Put>
  void ints(std::int64_t n, ScalarType s, const std::string& what, Put&& put) {
    std::int64_t v = 0;
    values(
        n, s, what,
        [&](std::int64_t i, std::string_view w) {
          if (!parse_int64(w, v)) fail(what + ": '" + std::string(w.substr(0, 40)) + "' is not an integer");
          put(i, v);
        },
        [&](std::int64_t i, const char* p) {
          if (!load_as_int64(p, s, true, v)) fail(what + ": value " + std::to_string(i) + " is not an integer");
          put(i, v);
        });
  }
  std::size_t& pos() { return pos_; }
  std::size_t& line() { return line_; }

 private:
  std::string_view d_;
  const std::string& path_;
  bool binary_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
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

// The arrays of a "FIELD name n" block (the keyword already read); those
// with `tuples` tuples (any count when tuples < 0 is not kept) go to fields.
void read_field_block(Reader& r, std::int64_t tuples, std::vector<Field>& fields) {
  r.word();  // the field data's name
  const std::int64_t arrays = r.count("FIELD array count");
  for (std::int64_t a = 0; a < arrays; ++a) {
    const std::string name = unescape_name(r.word());
    if (upper(name) == "METADATA") {  // 5.x: METADATA blocks may follow an array
      r.skip_metadata();
      --a;
      continue;
    }
    const std::int64_t comps = r.count("component count");
    const std::int64_t n = r.count("tuple count");
    ScalarType s;
    const std::string_view t = r.word();
    if (!legacy_type(t, s)) r.fail("unknown data type '" + std::string(t.substr(0, 40)) + "' of FIELD array " + name);
    if (comps < 1 || comps > 4096) r.fail("FIELD array " + name + " has " + std::to_string(comps) + " components");
    Array<float> v = r.floats(n * comps, s, "FIELD array " + name);
    if (tuples >= 0 && n == tuples) fields.push_back(Field{name, int(comps), std::move(v)});
  }
}

// Reads the attribute arrays of one POINT_DATA or CELL_DATA section into
// `fields` until the next section keyword (returned, "" at the end).
std::string read_attributes(Reader& r, std::int64_t tuples, std::vector<Field>& fields) {
  while (!r.at_end()) {
    const std::string key = upper(r.word());
    if (key == "POINT_DATA" || key == "CELL_DATA" || key == "POINTS" || key == "CELLS" || key == "CELL_TYPES")
      return key;
    if (key == "METADATA") {
      r.skip_metadata();
      continue;
    }
    if (key == "SCALARS" || key == "VECTORS" || key == "NORMALS" || key == "TEXTURE_COORDINATES" ||
        key == "TENSORS" || key == "TENSORS6" || key == "COLOR_SCALARS") {
      const std::string name = unescape_name(r.word());
      std::int64_t comps = key == "SCALARS" ? 1 : key == "TENSORS" ? 9 : key == "TENSORS6" ? 6 : 3;
      ScalarType s = ScalarType::Float32;
      if (key == "COLOR_SCALARS") {
        comps = r.count("component count");
        s = ScalarType::UInt8;  // BINARY color scalars are unsigned chars; ASCII are floats in [0, 1]
      } else {
        const std::string_view t = r.word();
        if (!legacy_type(t, s)) r.fail("unknown data type '" + std::string(t.substr(0, 40)) + "' of " + name);
        if (key == "TEXTURE_COORDINATES") comps = r.count("component count");
      }
      if (key == "SCALARS") {
        // An optional component count on the same line, then an optional LOOKUP_TABLE line.
        std::size_t save = r.pos(), line = r.line();
        const std::string_view w = r.word();
        std::int64_t c = 0;
        if (r.line() == line && parse_int64(w, c)) comps = c;
        else r.pos() = save, r.line() = line;
        save = r.pos(), line = r.line();
        if (upper(r.word()) == "LOOKUP_TABLE") r.word();
        else r.pos() = save, r.line() = line;
      }
      if (comps < 1 || comps > 4096) r.fail("array " + name + " has " + std::to_string(comps) + " components");
      fields.push_back(Field{key == "NORMALS" ? std::string("Normals") : name, int(comps),
                             r.floats(tuples * comps, s, name)});
      continue;
    }
    if (key == "LOOKUP_TABLE") {  // a table of colours given in the data section
      r.word();
      const std::int64_t n = r.count("lookup table size");
      r.floats(4 * n, ScalarType::UInt8, "LOOKUP_TABLE");
      continue;
    }
    if (key == "FIELD") {
      read_field_block(r, tuples, fields);
      continue;
    }
    r.fail("unexpected keyword '" + key.substr(0, 40) + "'");
  }
  return "";
}

// The file's first lines: magic, title, ASCII|BINARY, then "DATASET
// UNSTRUCTURED_GRID"; returns a reader at the first section.
Reader open_grid(std::string_view data, const std::string& path) {
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
  if (!binary && mode.rfind("ASCII", 0) != 0)
    throw InputError(path + ": legacy VTK format is '" + mode.substr(0, 40) + "', not ASCII or BINARY");
  Reader r(data.substr(p), path, binary);
  r.line() = 4;
  if (upper(r.word()) != "DATASET") r.fail("expected DATASET");
  const std::string dataset = upper(r.word());
  if (dataset != "UNSTRUCTURED_GRID")
    r.fail("dataset is " + dataset.substr(0, 40) + ", not UNSTRUCTURED_GRID (keymesh reads unstructured grids from .vtk)");
  return r;
}

// The sections of an unstructured grid, in the order the file gives them,
// read into one grid.
class GridSections {
 public:
  explicit GridSections(Reader& r) : r_(r) {}

  // Reads sections up to the end of the file.
  void read_all() {
    std::string next;
    while (!next.empty() || !r_.at_end()) {
      const std::string key = next.empty() ? upper(r_.word()) : next;
      next.clear();
      if (key == "POINTS") {
        points();
      } else if (key == "CELLS") {
        cells();
      } else if (key == "CELL_TYPES") {
        cell_types();
      } else if (key == "POINT_DATA" || key == "CELL_DATA") {
        next = data(key);
      } else if (key == "FIELD") {
        std::vector<Field> ignored;  // dataset-level field data (time value, ...) is not kept
        read_field_block(r_, -1, ignored);
      } else if (key == "METADATA") {
        r_.skip_metadata();
      } else {
        r_.fail("unexpected keyword '" + key.substr(0, 40) + "'");
      }
    }
  }

  UnstructuredGrid finish(const std::string& path);

 private:
  // Ids are checked against the point count as they are read when POINTS
  // came first (as every writer puts it); otherwise validate() checks them.
  std::uint64_t id_limit() const { return npts_ >= 0 ? std::uint64_t(npts_) : std::uint64_t{1} << 62; }
  std::uint64_t read_id(std::int64_t v, std::int64_t i, const char* what) {
    if (v < 0 || std::uint64_t(v) >= id_limit())
      r_.fail(std::string(what) + ": point id " + std::to_string(v) + " at connectivity[" + std::to_string(i) +
              "] is out of range (" + std::to_string(npts_) + " points)");
    return std::uint64_t(v);
  }

  void points() {
    if (npts_ >= 0) r_.fail("a second POINTS section");
    npts_ = r_.count("point count");
    ScalarType s;
    const std::string_view t = r_.word();
    if (!legacy_type(t, s)) r_.fail("unknown point type '" + std::string(t.substr(0, 40)) + "'");
    g_.points = r_.floats(3 * npts_, s, "POINTS");
  }

  void cells() {
    if (have_cells_) r_.fail("a second CELLS section");
    have_cells_ = true;
    ids_unchecked_ = npts_ < 0;
    const std::int64_t a = r_.count("cell count"), b = r_.count("CELLS size");
    const std::size_t save = r_.pos(), save_line = r_.line();
    if (upper(r_.word()) == "OFFSETS") {
      offsets_and_connectivity(a, b);
    } else {
      r_.pos() = save, r_.line() = save_line;
      counted_cells(a, b);
    }
  }

  // 5.x: "CELLS offsets_count connectivity_count" then OFFSETS and CONNECTIVITY arrays.
  void offsets_and_connectivity(std::int64_t a, std::int64_t b) {
    ScalarType s;
    if (!legacy_type(r_.word(), s)) r_.fail("bad OFFSETS type");
    ncells_ = a > 0 ? a - 1 : 0;
    r_.check_count(a, s, "OFFSETS");
    g_.offsets.resize(std::size_t(a));
    r_.ints(a, s, "OFFSETS", [&](std::int64_t i, std::int64_t v) {
      if (v < 0 || v > b) r_.fail("OFFSETS: offset " + std::to_string(v) + " of cell " + std::to_string(i) +
                                  " is outside the connectivity (" + std::to_string(b) + " ids)");
      g_.offsets[std::size_t(i)] = std::uint64_t(v);
    });
    if (upper(r_.word()) != "CONNECTIVITY") r_.fail("expected CONNECTIVITY after OFFSETS");
    if (!legacy_type(r_.word(), s)) r_.fail("bad CONNECTIVITY type");
    r_.check_count(b, s, "CONNECTIVITY");
    g_.connectivity = IndexArray::for_ids(id_limit(), std::size_t(b));
    r_.ints(b, s, "CONNECTIVITY", [&](std::int64_t i, std::int64_t v) {
      g_.connectivity.set(std::size_t(i), read_id(v, i, "CONNECTIVITY"));
    });
    if (a == 0) g_.offsets.assign(1, 0);
  }

  // Classic: "CELLS n size", then per cell its corner count and ids.
  void counted_cells(std::int64_t a, std::int64_t b) {
    ncells_ = a;
    if (b < a) r_.fail("CELLS size " + std::to_string(b) + " is smaller than the cell count " + std::to_string(a));
    r_.check_count(b, ScalarType::Int32, "CELLS");
    const std::uint64_t nids = std::uint64_t(b - a);
    g_.connectivity = IndexArray::for_ids(id_limit(), std::size_t(nids));
    g_.offsets.assign(std::size_t(a) + 1, 0);
    std::uint64_t at = 0;    // ids stored so far
    std::int64_t cell = 0;   // cells started so far
    std::uint64_t left = 0;  // ids still due for the current cell
    r_.ints(b, ScalarType::Int32, "CELLS", [&](std::int64_t i, std::int64_t v) {
      if (left > 0) {
        g_.connectivity.set(std::size_t(at), read_id(v, std::int64_t(at), "CELLS"));
        ++at, --left;
        return;
      }
      if (cell >= a || v < 0 || std::uint64_t(v) > nids - at)
        r_.fail("CELLS list is inconsistent at cell " + std::to_string(cell) + " (entry " + std::to_string(i) +
                ": " + std::to_string(v) + ")");
      left = std::uint64_t(v);
      g_.offsets[std::size_t(++cell)] = at + left;
    });
    if (cell != a || left != 0 || at != nids)
      r_.fail("CELLS size " + std::to_string(b) + " does not match the " + std::to_string(a) + " cells listed");
  }

  void cell_types() {
    if (have_types_) r_.fail("a second CELL_TYPES section");
    have_types_ = true;
    const std::int64_t n = r_.count("cell type count");
    r_.check_count(n, ScalarType::Int32, "CELL_TYPES");
    g_.cell_types.resize(std::size_t(n));
    r_.ints(n, ScalarType::Int32, "CELL_TYPES", [&](std::int64_t i, std::int64_t v) {
      if (v < 0 || v > 255) r_.fail("CELL_TYPES: cell " + std::to_string(i) + " has type " + std::to_string(v));
      g_.cell_types[std::size_t(i)] = static_cast<std::uint8_t>(v);
    });
  }

  // A POINT_DATA or CELL_DATA section; returns the keyword that ended it.
  std::string data(const std::string& key) {
    const bool points = key == "POINT_DATA";
    const std::int64_t n = r_.count("tuple count");
    const std::int64_t expected = points ? npts_ : ncells_;
    if (expected >= 0 && n != expected)
      r_.fail(key + " " + std::to_string(n) + " does not match the " + std::to_string(expected) +
              (points ? " points" : " cells"));
    return read_attributes(r_, n, points ? g_.point_fields : g_.cell_fields);
  }

  Reader& r_;
  UnstructuredGrid g_;
  std::int64_t npts_ = -1, ncells_ = -1;
  bool have_cells_ = false, have_types_ = false;
  bool ids_unchecked_ = false;  // CELLS before POINTS: ids checked by validate() at the end
};

// One fixed-size type throughout: the grid stores it uniformly.
void store_uniform_type(UnstructuredGrid& g, std::int64_t ncells) {
  const int k = cell_type_size(static_cast<CellType>(g.cell_types[0]));
  bool uniform = k > 0 && g.offsets.size() == std::size_t(ncells) + 1 && g.offsets.front() == 0;
  for (std::size_t c = 0; uniform && c + 1 < g.offsets.size(); ++c)
    uniform = g.offsets[c + 1] >= g.offsets[c] && g.offsets[c + 1] - g.offsets[c] == std::uint64_t(k);
  if (uniform && g.offsets.back() == g.connectivity.size()) {
    g.uniform_type = static_cast<CellType>(g.cell_types[0]);
    g.offsets.clear();
    g.cell_types.clear();
  }
}

// The checks of the whole grid, once every section is read.
UnstructuredGrid GridSections::finish(const std::string& path) {
  UnstructuredGrid& g = g_;
  if (npts_ < 0) throw InputError(path + ": legacy VTK file has no POINTS");
  const std::int64_t ncells = ncells_ < 0 ? 0 : ncells_;
  if (std::int64_t(g.cell_types.size()) != ncells)
    throw InputError(path + ": " + std::to_string(g.cell_types.size()) + " CELL_TYPES for " + std::to_string(ncells) +
                     " cells");
  if (ncells == 0) {
    g.offsets.clear();
    g.cell_types.clear();
  } else if (std::all_of(g.cell_types.begin(), g.cell_types.end(), [&](std::uint8_t t) { return t == g.cell_types[0]; })) {
    store_uniform_type(g, ncells);
  }
  if (!g.offsets.empty() && std::int64_t(g.offsets.size()) != ncells + 1)
    throw InputError(path + ": " + std::to_string(g.offsets.size()) + " cell offsets for " + std::to_string(ncells) +
                     " cells");
  g.validate(path, ids_unchecked_);
  return std::move(g);
}

}  // namespace

std::string legacy_vtk_dataset(const std::string& path) {
  InputFile file(path);
  std::FILE* in = file.stream();
  std::string line;
  auto get = [&] {
    // Header lines are short: a file whose first bytes hold no newline is not legacy VTK.
    line.clear();
    int c = 0;
    while (line.size() < 1024 && (c = std::fgetc(in)) != EOF && c != '\n') line.push_back(static_cast<char>(c));
    return c != EOF || !line.empty();
  };
  if (!get() || line.rfind("# vtk DataFile", 0) != 0) return "";
  for (int i = 0; i < 3 && get(); ++i) {
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

// The header, every section, then the checks of the whole grid.
UnstructuredGrid parse_legacy_vtk(std::string_view data, const std::string& path) {
  Reader r = open_grid(data, path);
  GridSections sections(r);
  sections.read_all();
  return sections.finish(path);
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
