#include "mesh_formats.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "mesh_bytes.hpp"

#include "checked_mesh.hpp"
#include "type_names.hpp"

namespace keymesh::io {

using namespace mesh_bytes;

SurfaceMesh read_ply(const std::string& path) { return parse_ply(read_whole_file(path), path); }

namespace {

enum class Format { Ascii, BinaryLittle, BinaryBig };

struct Property {
  std::string name;
  bool is_list = false;
  ScalarType type = ScalarType::Float32;        // scalar type, or list item type
  ScalarType count_type = ScalarType::UInt8;    // list count type
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> props;
};

// PLY's type names, the original ones and the sized ones of later writers.
constexpr TypeName kPlyTypes[] = {
    {"char", ScalarType::Int8},     {"int8", ScalarType::Int8},       {"uchar", ScalarType::UInt8},
    {"uint8", ScalarType::UInt8},   {"short", ScalarType::Int16},     {"int16", ScalarType::Int16},
    {"ushort", ScalarType::UInt16}, {"uint16", ScalarType::UInt16},   {"int", ScalarType::Int32},
    {"int32", ScalarType::Int32},   {"uint", ScalarType::UInt32},     {"uint32", ScalarType::UInt32},
    {"float", ScalarType::Float32}, {"float32", ScalarType::Float32}, {"double", ScalarType::Float64},
    {"float64", ScalarType::Float64},
};

std::optional<ScalarType> ply_scalar(std::string_view t) { return type_named(t, kPlyTypes); }

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const std::size_t s = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > s) words.push_back(line.substr(s, i - s));
  }
  return words;
}

// Reads values one at a time from the body, whatever its encoding.
class ValueReader {
 public:
  ValueReader(std::string_view body, Format format, const std::string& path)
      : format_(format), bytes_(body, path), text_(body), path_(path) {}

  double read_double(ScalarType s, std::string_view what) {
    if (format_ != Format::Ascii) return load_as_double(bytes_.take(scalar_size(s), what), s, big());
    const std::string_view t = token(what);
    double v = 0;
    if (!parse_double(t, v)) bad_token(t, what);
    return v;
  }

  std::int64_t read_int(ScalarType s, std::string_view what) {
    std::int64_t v = 0;
    if (format_ != Format::Ascii) {
      if (!load_as_int64(bytes_.take(scalar_size(s), what), s, big(), v))
        throw InputError(path_ + ": " + std::string(what) + " is not an integer");
      return v;
    }
    const std::string_view t = token(what);
    if (parse_int64(t, v)) return v;
    double d = 0;
    if (parse_double(t, d) && d == std::floor(d) && std::fabs(d) < 9.0e18) return static_cast<std::int64_t>(d);
    bad_token(t, what);
  }

  void skip(const Property& p, std::string_view what) {
    if (p.is_list) {
      const std::int64_t n = read_int(p.count_type, what);
      if (n < 0) throw InputError(path_ + ": negative list size in " + std::string(what));
      if (format_ != Format::Ascii) {
        bytes_.take(static_cast<std::size_t>(n) * scalar_size(p.type), what);
      } else {
        for (std::int64_t i = 0; i < n; ++i) token(what);
      }
    } else if (format_ != Format::Ascii) {
      bytes_.take(scalar_size(p.type), what);
    } else {
      token(what);
    }
  }

  std::size_t remaining() const { return format_ == Format::Ascii ? text_remaining() : bytes_.remaining(); }

  // A binary body's bytes at the cursor, for the readers of whole records
  // (read_binary_vertices, read_binary_faces), and a step over those read.
  bool binary() const { return format_ != Format::Ascii; }
  bool big() const { return format_ == Format::BinaryBig; }
  const char* here() const { return bytes_.here(); }
  void step(std::size_t n, std::string_view what) { bytes_.take(n, what); }

 private:
  std::size_t text_remaining() const { return body_size() - text_.pos(); }
  std::size_t body_size() const { return bytes_.pos() + bytes_.remaining(); }

  std::string_view token(std::string_view what) {
    const std::string_view t = text_.next();
    if (t.empty()) throw InputError(path_ + ": truncated file: missing value for " + std::string(what));
    return t;
  }
  [[noreturn]] void bad_token(std::string_view t, std::string_view what) {
    throw InputError(path_ + ": line " + std::to_string(text_.line()) + ": bad number '" +
                     std::string(t.substr(0, 40)) + "' for " + std::string(what));
  }

  Format format_;
  ByteCursor bytes_;
  TokenCursor text_;
  const std::string& path_;
};

// The header: the body's encoding, the elements in file order, and where the
// body starts.
struct Header {
  Format format = Format::Ascii;
  std::vector<Element> elements;
  std::size_t body = 0;
};

std::string header_line_text(std::string_view line) { return "'" + std::string(line.substr(0, 80)) + "'"; }

Format parse_format(const std::vector<std::string_view>& w, const std::string& path) {
  if (w.size() < 2) throw InputError(path + ": PLY format line without a format");
  if (w[1] == "ascii") return Format::Ascii;
  if (w[1] == "binary_little_endian") return Format::BinaryLittle;
  if (w[1] == "binary_big_endian") return Format::BinaryBig;
  throw InputError(path + ": unknown PLY format '" + std::string(w[1]) + "'");
}

// "property <type> <name>" or "property list <count type> <item type> <name>".
Property parse_property(const std::vector<std::string_view>& w, std::string_view line, const std::string& path) {
  Property p;
  if (w.size() >= 5 && w[1] == "list") {
    const auto ct = ply_scalar(w[2]);
    const auto it = ply_scalar(w[3]);
    if (!ct || !it) throw InputError(path + ": unknown PLY type in " + header_line_text(line));
    if (scalar_is_float(*ct)) throw InputError(path + ": PLY list count type must be an integer type");
    p.is_list = true;
    p.count_type = *ct;
    p.type = *it;
    p.name = std::string(w[4]);
  } else if (w.size() >= 3) {
    const auto t = ply_scalar(w[1]);
    if (!t) throw InputError(path + ": unknown PLY type in " + header_line_text(line));
    p.type = *t;
    p.name = std::string(w[2]);
  } else {
    throw InputError(path + ": bad PLY property line " + header_line_text(line));
  }
  return p;
}

Header read_header(std::string_view data, const std::string& path) {
  std::size_t pos = 0;
  auto next_line = [&](std::string_view& line) {
    if (pos >= data.size()) return false;
    std::size_t end = data.find('\n', pos);
    const bool has_newline = end != std::string_view::npos;
    if (!has_newline) end = data.size();
    line = data.substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = has_newline ? end + 1 : end;
    return true;
  };
  std::string_view line;
  if (!next_line(line) || line != "ply") throw InputError(path + ": not a PLY file (missing 'ply' magic)");
  Header h;
  std::optional<Format> format;
  bool ended = false;
  while (!ended && next_line(line)) {
    const auto w = split_words(line);
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      ended = true;
    } else if (w[0] == "format") {
      format = parse_format(w, path);
    } else if (w[0] == "element") {
      std::int64_t count = 0;
      if (w.size() < 3 || !parse_int64(w[2], count) || count < 0)
        throw InputError(path + ": bad PLY element line " + header_line_text(line));
      h.elements.push_back({std::string(w[1]), static_cast<std::uint64_t>(count), {}});
    } else if (w[0] == "property") {
      if (h.elements.empty()) throw InputError(path + ": PLY property before any element");
      h.elements.back().props.push_back(parse_property(w, line, path));
    } else {
      throw InputError(path + ": unknown PLY header line " + header_line_text(line));
    }
  }
  if (!ended) throw InputError(path + ": truncated PLY header (no end_header)");
  if (!format) throw InputError(path + ": PLY header has no format line");
  h.format = *format;
  h.body = pos;
  return h;
}

// Refuses a record count the rest of the file cannot hold, before anything
// is allocated for it.
void check_record_count(const Element& e, const ValueReader& in, bool ascii, const std::string& path) {
  std::uint64_t min_record = 0;
  for (const auto& p : e.props) min_record += ascii ? 2 : scalar_size(p.is_list ? p.count_type : p.type);
  if (e.count > (in.remaining() + 1) / min_record)
    throw InputError(path + ": element '" + e.name + "' declares " + std::to_string(e.count) +
                     " records, more than the file can hold");
}

// A vertex-element field read from one or more scalar properties.
struct FieldPlan {
  std::string name;
  std::vector<std::size_t> props;  // property indices, one per component
};

// Where each vertex property goes: a coordinate, a field component, or
// nowhere (list properties, skipped).
struct VertexLayout {
  std::vector<FieldPlan> fields;
  std::vector<int> coordinate;                                  // 0..2 for x y z, -1 otherwise
  std::vector<std::pair<std::size_t, std::size_t>> field_slot;  // (field, component) of the others
};

// The fields of the scalar properties not `used` (x y z, nx ny nz, taken
// by the caller): runs p_0, p_1, ... as one field "p" (as keymesh writes
// multi-component fields), every other property as a 1-component field.
std::vector<FieldPlan> plan_fields(const Element& e, const std::vector<bool>& used) {
  std::vector<FieldPlan> plans;
  for (std::size_t i = 0; i < e.props.size();) {
    const auto& p = e.props[i];
    if (p.is_list || used[i]) {
      ++i;
      continue;
    }
    std::size_t run = 0;
    std::string base;
    if (p.name.size() > 2 && p.name.compare(p.name.size() - 2, 2, "_0") == 0) {
      base = p.name.substr(0, p.name.size() - 2);
      while (i + run < e.props.size() && !e.props[i + run].is_list &&
             e.props[i + run].name == base + "_" + std::to_string(run))
        ++run;
    }
    if (run >= 2) {
      FieldPlan plan{base, {}};
      for (std::size_t k = 0; k < run; ++k) plan.props.push_back(i + k);
      plans.push_back(std::move(plan));
      i += run;
    } else {
      plans.push_back({p.name, {i}});
      ++i;
    }
  }
  return plans;
}

// The vertex fields: nx ny nz as "Normals", then plan_fields of the others.
std::vector<FieldPlan> plan_vertex_fields(const Element& e, const std::size_t xyz[3],
                                          const std::optional<std::size_t> nxyz[3]) {
  const bool normals = nxyz[0] && nxyz[1] && nxyz[2];
  std::vector<bool> used(e.props.size(), false);
  for (int a = 0; a < 3; ++a) used[xyz[a]] = true;
  std::vector<FieldPlan> plans;
  if (normals) {
    plans.push_back({"Normals", {*nxyz[0], *nxyz[1], *nxyz[2]}});
    for (int a = 0; a < 3; ++a) used[*nxyz[a]] = true;
  }
  for (FieldPlan& plan : plan_fields(e, used)) plans.push_back(std::move(plan));
  return plans;
}

// Where each planned property's value goes: (field, component), or
// (SIZE_MAX, 0) for none; the fields made with their names and components.
std::vector<std::pair<std::size_t, std::size_t>> field_slots(const Element& e, const std::vector<FieldPlan>& plans) {
  std::vector<std::pair<std::size_t, std::size_t>> slot(e.props.size(), {SIZE_MAX, 0});
  for (std::size_t f = 0; f < plans.size(); ++f)
    for (std::size_t k = 0; k < plans[f].props.size(); ++k) slot[plans[f].props[k]] = {f, k};
  return slot;
}

void make_fields(const std::vector<FieldPlan>& plans, std::uint64_t tuples, std::vector<Field>& fields) {
  fields.resize(plans.size());
  for (std::size_t f = 0; f < plans.size(); ++f) {
    fields[f].name = plans[f].name;
    fields[f].components = static_cast<int>(plans[f].props.size());
    fields[f].values.resize(tuples * plans[f].props.size());
  }
}

VertexLayout plan_vertex(const Element& e, const std::string& path) {
  std::optional<std::size_t> found[6];  // x y z nx ny nz
  static const char* const kNames[6] = {"x", "y", "z", "nx", "ny", "nz"};
  for (std::size_t i = 0; i < e.props.size(); ++i) {
    if (e.props[i].is_list) continue;
    for (int k = 0; k < 6; ++k)
      if (e.props[i].name == kNames[k]) found[k] = i;
  }
  if (!found[0] || !found[1] || !found[2]) throw InputError(path + ": PLY vertex element lacks x, y or z");
  const std::size_t xyz[3] = {*found[0], *found[1], *found[2]};
  VertexLayout layout;
  layout.fields = plan_vertex_fields(e, xyz, found + 3);
  layout.coordinate.assign(e.props.size(), -1);
  for (int a = 0; a < 3; ++a) layout.coordinate[xyz[a]] = a;
  layout.field_slot = field_slots(e, layout.fields);
  return layout;
}

// A binary vertex element of scalars only, record by record in place: each
// property's value at its offset, converted as the value-by-value path does
// (through double; a float32 NaN goes that way too, which quiets a
// signalling one), for the records the body holds whole. Returns how many it
// read; the value-by-value path reads the rest and names what is missing.
std::uint64_t read_binary_vertices(const Element& e, const VertexLayout& layout, ValueReader& in, SurfaceMesh& mesh) {
  if (!in.binary()) return 0;
  struct Slot {
    std::size_t offset;
    ScalarType type;
    float* out;
    std::size_t step;
  };
  std::vector<Slot> slots;
  std::size_t stride = 0;
  for (std::size_t i = 0; i < e.props.size(); ++i) {
    const Property& p = e.props[i];
    if (p.is_list) return 0;
    if (layout.coordinate[i] >= 0) {
      slots.push_back({stride, p.type, mesh.points.data() + layout.coordinate[i], 3});
    } else {
      const auto [f, k] = layout.field_slot[i];
      Field& fd = mesh.point_fields[f];
      slots.push_back({stride, p.type, fd.values.data() + k, static_cast<std::size_t>(fd.components)});
    }
    stride += scalar_size(p.type);
  }
  const std::uint64_t whole = std::min<std::uint64_t>(e.count, in.remaining() / stride);
  const bool big = in.big();
  const char* record = in.here();
  // x y z as float32, little-endian, and nothing else (what keymesh and
  // most tools write): the records are the points array. (A coordinate's NaN
  // is refused by checked_mesh whatever its bits.)
  if (!big && stride == 12 && slots.size() == 3 && mesh.point_fields.empty()) {
    bool plain = true;
    for (int a = 0; a < 3; ++a)
      plain = plain && slots[a].type == ScalarType::Float32 && slots[a].offset == 4 * std::size_t(a) &&
              slots[a].out == mesh.points.data() + a;
    if (plain) {
      if (whole) std::memcpy(mesh.points.data(), record, 12 * whole);  // no points: data() may be null
      in.step(12 * whole, "vertices");
      return whole;
    }
  }
  // A block of records at a time, one property after the other over it (a
  // tight loop per property, the block still in cache).
  constexpr std::uint64_t kBlock = 4096;
  for (std::uint64_t b = 0; b < whole; b += kBlock) {
    const std::uint64_t e_block = std::min(whole, b + kBlock);
    for (const Slot& s : slots) {
      const char* at = record + b * stride + s.offset;
      float* out = s.out + b * s.step;
      if (s.type == ScalarType::Float32 && !big) {
        for (std::uint64_t r = b; r < e_block; ++r, at += stride, out += s.step) {
          float v;
          std::memcpy(&v, at, sizeof v);
          *out = v == v ? v : static_cast<float>(load_as_double(at, s.type, big));
        }
      } else {
        for (std::uint64_t r = b; r < e_block; ++r, at += stride, out += s.step)
          *out = static_cast<float>(load_as_double(at, s.type, big));
      }
    }
  }
  in.step(whole * stride, "vertices");
  return whole;
}

void read_vertices(const Element& e, ValueReader& in, SurfaceMesh& mesh, const std::string& path) {
  if (e.count > std::numeric_limits<PointIndex>::max())
    throw LimitError(path + ": " + std::to_string(e.count) + " vertices exceed 2^32 - 1");
  const VertexLayout layout = plan_vertex(e, path);
  const std::string what = "element '" + e.name + "'";
  mesh.points.resize(3 * e.count);
  make_fields(layout.fields, e.count, mesh.point_fields);
  for (std::uint64_t r = read_binary_vertices(e, layout, in, mesh); r < e.count; ++r) {
    for (std::size_t i = 0; i < e.props.size(); ++i) {
      const auto& p = e.props[i];
      if (p.is_list) {
        in.skip(p, what);
      } else if (layout.coordinate[i] >= 0) {
        mesh.points[3 * r + layout.coordinate[i]] = static_cast<float>(in.read_double(p.type, what));
      } else {
        const auto [f, k] = layout.field_slot[i];
        Field& fd = mesh.point_fields[f];
        fd.values[r * fd.components + k] = static_cast<float>(in.read_double(p.type, what));
      }
    }
  }
}

// One face's vertex_indices list, appended to the mesh's cells.
void read_face(const Property& p, std::uint64_t r, std::uint64_t num_points, ValueReader& in, SurfaceMesh& mesh,
               const std::string& what, const std::string& path) {
  const std::int64_t n = in.read_int(p.count_type, what);
  if (n < 3)
    throw InputError(path + ": face " + std::to_string(r) + " has " + std::to_string(n) +
                     " vertices (at least 3 needed)");
  if (static_cast<std::uint64_t>(n) > in.remaining())
    throw InputError(path + ": truncated file: face " + std::to_string(r) + " declares " + std::to_string(n) +
                     " vertices");
  for (std::int64_t k = 0; k < n; ++k) {
    const std::int64_t id = in.read_int(p.type, what);
    if (id < 0 || static_cast<std::uint64_t>(id) >= num_points)
      throw InputError(path + ": face " + std::to_string(r) + " refers to vertex " + std::to_string(id) +
                       " out of range (" + std::to_string(num_points) + " vertices)");
    mesh.connectivity.push_back(static_cast<PointIndex>(id));
  }
  mesh.offsets.push_back(mesh.connectivity.size());
}

// The face layout nearly every binary PLY has (a one-byte count, 32-bit
// ids, nothing else per face, little-endian): 13-byte triangles, their ids
// written in place, for as long as each is a triangle with ids in range.
// Offsets are made only when a face that is not such follows (a triangle
// mesh has none). Returns how many faces it read.
std::uint64_t read_binary_triangles(const Element& e, std::size_t list, std::uint64_t num_points, ValueReader& in,
                                    SurfaceMesh& mesh) {
  const Property& p = e.props[list];
  if (!in.binary() || in.big() || e.props.size() != 1 || scalar_size(p.count_type) != 1 ||
      (p.type != ScalarType::Int32 && p.type != ScalarType::UInt32) || !mesh.connectivity.empty())
    return 0;
  constexpr std::size_t kRecord = 13;
  // Ids read as unsigned: a negative int32 is then 2^31 or more.
  const std::uint64_t limit =
      p.type == ScalarType::Int32 ? std::min<std::uint64_t>(num_points, std::uint64_t{1} << 31) : num_points;
  const std::uint64_t whole = std::min<std::uint64_t>(e.count, in.remaining() / kRecord);
  mesh.connectivity.resize(3 * whole);
  PointIndex* out = mesh.connectivity.data();
  const char* face = in.here();
  std::uint64_t r = 0;
  for (; r < whole; ++r, face += kRecord, out += 3) {
    std::uint32_t id[3];
    std::memcpy(id, face + 1, sizeof id);
    if (face[0] != 3 || id[0] >= limit || id[1] >= limit || id[2] >= limit) break;
    out[0] = id[0], out[1] = id[1], out[2] = id[2];
  }
  mesh.connectivity.resize(3 * r);
  in.step(r * kRecord, "faces");
  if (r < e.count) {
    mesh.offsets.resize(r + 1);
    for (std::uint64_t k = 0; k <= r; ++k) mesh.offsets[k] = 3 * k;
  }
  return r;
}

// A binary face element whose only list is the vertex indices, face by face
// in place, for as long as each face is whole in the body, has at least
// three ids, all in range: no value is read twice and no call is made per
// value; the other properties' values go to the cell fields by `slot`.
// From face `first` on; returns the first face it did not read, from
// which the value-by-value path reads (and names what is wrong).
std::uint64_t read_binary_faces(const Element& e, std::size_t list, std::uint64_t num_points, ValueReader& in,
                                SurfaceMesh& mesh, std::uint64_t first,
                                const std::vector<std::pair<std::size_t, std::size_t>>& slot) {
  if (!in.binary() || first == e.count) return first;
  struct Value {
    std::size_t offset;  // from the record's start (before the list) or the ids' end (after it)
    bool after;
    ScalarType type;
    Field* field;
    std::size_t component;
  };
  std::vector<Value> values;
  std::size_t before = 0, after = 0;  // the other properties' bytes
  for (std::size_t i = 0; i < e.props.size(); ++i) {
    if (i == list) continue;
    if (e.props[i].is_list) return first;
    std::size_t& at = i < list ? before : after;
    if (slot[i].first != SIZE_MAX)
      values.push_back({at, i > list, e.props[i].type, &mesh.cell_fields[slot[i].first], slot[i].second});
    at += scalar_size(e.props[i].type);
  }
  const Property& p = e.props[list];
  const std::size_t count_bytes = scalar_size(p.count_type), id_bytes = scalar_size(p.type);
  const bool big = in.big();
  const bool plain_ids = !big && (p.type == ScalarType::Int32 || p.type == ScalarType::UInt32);
  auto id_at = [&](const char* at, std::int64_t& id) {
    if (plain_ids) {
      std::uint32_t u;
      std::memcpy(&u, at, sizeof u);
      id = p.type == ScalarType::Int32 ? std::int64_t{static_cast<std::int32_t>(u)} : std::int64_t{u};
      return true;
    }
    return load_as_int64(at, p.type, big, id);
  };
  const char* const begin = in.here();
  const char* face = begin;
  const std::size_t body = in.remaining();
  std::uint64_t r = first;
  for (; r < e.count; ++r) {
    const std::size_t left = body - static_cast<std::size_t>(face - begin);
    if (left < before + count_bytes) break;
    std::int64_t n = 0;
    if (p.count_type == ScalarType::UInt8) n = static_cast<unsigned char>(face[before]);
    else if (!load_as_int64(face + before, p.count_type, big, n)) break;
    if (n < 3 || static_cast<std::uint64_t>(n) > (left - before - count_bytes) / id_bytes) break;
    const char* const ids = face + before + count_bytes;
    const std::size_t record = before + count_bytes + static_cast<std::size_t>(n) * id_bytes + after;
    if (record > left) break;
    bool in_range = true;
    for (std::int64_t k = 0; k < n && in_range; ++k) {
      std::int64_t id = 0;
      in_range = id_at(ids + k * id_bytes, id) && id >= 0 && static_cast<std::uint64_t>(id) < num_points;
    }
    if (!in_range) break;
    for (std::int64_t k = 0; k < n; ++k) {
      std::int64_t id = 0;
      id_at(ids + k * id_bytes, id);
      mesh.connectivity.push_back(static_cast<PointIndex>(id));
    }
    for (const Value& v : values) {
      const char* at = (v.after ? ids + static_cast<std::size_t>(n) * id_bytes : face) + v.offset;
      v.field->values[r * static_cast<std::uint64_t>(v.field->components) + v.component] =
          static_cast<float>(load_as_double(at, v.type, big));
    }
    mesh.offsets.push_back(mesh.connectivity.size());
    face += record;
  }
  in.step(static_cast<std::size_t>(face - begin), "faces");
  return r;
}

void read_faces(const Element& e, std::uint64_t num_points, ValueReader& in, SurfaceMesh& mesh,
                const std::string& path) {
  std::optional<std::size_t> plist;
  for (std::size_t i = 0; i < e.props.size(); ++i)
    if (e.props[i].is_list && (e.props[i].name == "vertex_indices" || e.props[i].name == "vertex_index")) plist = i;
  if (!plist) throw InputError(path + ": PLY face element has no vertex_indices list");
  if (scalar_is_float(e.props[*plist].type)) throw InputError(path + ": PLY vertex_indices must be integers");
  const std::string what = "element '" + e.name + "'";
  // The face's scalar properties are cell fields (keymesh writes a cell
  // field's components as name_0, name_1, ...); other lists are skipped.
  std::vector<bool> used(e.props.size(), false);
  used[*plist] = true;
  const std::vector<FieldPlan> plans = plan_fields(e, used);
  const auto slot = field_slots(e, plans);
  make_fields(plans, e.count, mesh.cell_fields);
  mesh.offsets.reserve(e.count + 1);
  mesh.offsets.push_back(0);
  mesh.connectivity.reserve(3 * e.count);
  const std::uint64_t triangles = read_binary_triangles(e, *plist, num_points, in, mesh);
  for (std::uint64_t r = read_binary_faces(e, *plist, num_points, in, mesh, triangles, slot); r < e.count; ++r)
    for (std::size_t i = 0; i < e.props.size(); ++i) {
      if (i == *plist) {
        read_face(e.props[i], r, num_points, in, mesh, what, path);
      } else if (const auto [f, k] = slot[i]; f != SIZE_MAX) {
        Field& fd = mesh.cell_fields[f];
        fd.values[r * static_cast<std::uint64_t>(fd.components) + k] = static_cast<float>(in.read_double(e.props[i].type, what));
      } else {
        in.skip(e.props[i], what);
      }
    }
}

}  // namespace

// The header, then every element in file order: the vertex element, the
// first face element, and the others skipped.
SurfaceMesh parse_ply(std::string_view data, const std::string& path) {
  const Header header = read_header(data, path);
  const Element* vertex = nullptr;
  for (const auto& e : header.elements)
    if (e.name == "vertex") vertex = &e;
  const std::uint64_t num_points = vertex ? vertex->count : 0;

  SurfaceMesh mesh;
  ValueReader in(data.substr(header.body), header.format, path);
  bool have_faces = false;
  for (const Element& e : header.elements) {
    if (e.count == 0) continue;
    if (e.props.empty()) continue;  // nothing stored per record
    check_record_count(e, in, header.format == Format::Ascii, path);
    if (&e == vertex) {
      read_vertices(e, in, mesh, path);
    } else if (e.name == "face" && !have_faces) {
      read_faces(e, num_points, in, mesh, path);
      have_faces = true;
    } else {
      const std::string what = "element '" + e.name + "'";
      for (std::uint64_t r = 0; r < e.count; ++r)
        for (const auto& p : e.props) in.skip(p, what);
    }
  }
  compact_offsets(mesh);
  if (mesh.offsets.size() == 1) mesh.offsets.clear();  // a face element with no faces
  return checked_mesh(std::move(mesh), path);
}

namespace {

std::string ply_name(const std::string& name) {
  std::string out = name.empty() ? std::string("field") : name;
  for (char& c : out)
    if (is_space(c)) c = '_';  // a header word cannot hold whitespace
  return out;
}

// A field's property names: its own for one component, base_0, base_1, ...
// otherwise.
std::vector<std::string> property_names(const std::string& base, int components) {
  std::vector<std::string> names;
  if (components == 1) names.push_back(base);
  else
    for (int k = 0; k < components; ++k) names.push_back(base + "_" + std::to_string(k));
  return names;
}

// The "property float" lines of `fields`' components, each property once:
// a field whose PLY name is `taken` (x, nx, vertex_indices, or one named like
// another's component) is written as field_<name> (field_<name>_2, ...
// while that is taken too). With `normals`, the first 3-component field
// "Normals" is nx ny nz.
std::string field_properties(const std::vector<Field>& fields, std::set<std::string> taken, bool normals) {
  normals = normals && std::any_of(fields.begin(), fields.end(),
                                   [](const Field& f) { return f.name == "Normals" && f.components == 3; });
  if (normals) taken.insert({"nx", "ny", "nz"});
  std::string lines;
  bool normals_written = false;
  for (const Field& f : fields) {
    if (normals && f.name == "Normals" && f.components == 3 && !normals_written) {
      lines += "property float nx\nproperty float ny\nproperty float nz\n";
      normals_written = true;
      continue;
    }
    std::string base = ply_name(f.name);
    auto names = property_names(base, f.components);
    auto free = [&] {
      return std::none_of(names.begin(), names.end(), [&](const std::string& name) { return taken.count(name) > 0; });
    };
    for (int attempt = 1; !free(); ++attempt) {
      std::string renamed = "field_";
      renamed += base;
      if (attempt > 1) {
        renamed += '_';
        renamed.append(std::to_string(attempt));
      }
      names = property_names(renamed, f.components);
    }
    for (const std::string& name : names) {
      taken.insert(name);
      lines += "property float ";
      lines += name;
      lines += '\n';
    }
  }
  return lines;
}

// The vertex element's properties: x y z, then every point field's components.
std::string vertex_properties(const SurfaceMesh& mesh) {
  return "property float x\nproperty float y\nproperty float z\n" +
         field_properties(mesh.point_fields, {"x", "y", "z"}, true);
}

}  // namespace

namespace {

// The body of write_ply on a little-endian machine: records copied as they
// are in memory into a block, the block written when full (no append per
// value: this was more instructions than the contour that made the mesh).
// False, having written nothing, for a vertex record past a sixteenth of a
// block (thousands of field components): the caller's path writes it.
bool write_ply_records(const SurfaceMesh& mesh, bool wide_count, AtomicFile& file) {
  constexpr std::size_t kBlock = std::size_t{1} << 20;
  std::size_t vertex_bytes = 12;
  for (const Field& f : mesh.point_fields) vertex_bytes += 4 * static_cast<std::size_t>(f.components);
  if (vertex_bytes > kBlock / 16) return false;
  std::unique_ptr<char[]> block(new char[kBlock]);
  char* at = block.get();
  auto room = [&](std::size_t bytes) {
    if (static_cast<std::size_t>(at - block.get()) + bytes > kBlock) {
      file.write(block.get(), static_cast<std::size_t>(at - block.get()));
      at = block.get();
    }
  };
  auto put = [&](const void* data, std::size_t bytes) {
    std::memcpy(at, data, bytes);
    at += bytes;
  };
  const Id n = mesh.num_points(), cells = mesh.num_cells();
  // Whole blocks of records, checked for room once a block.
  auto by_blocks = [&](Id count, std::size_t record, auto&& write_one) {
    const Id per_block = static_cast<Id>(kBlock / record);
    for (Id b = 0; b < count; b += per_block) {
      const Id e = std::min(count, b + per_block);
      room(static_cast<std::size_t>(e - b) * record);
      for (Id i = b; i < e; ++i) write_one(i);
    }
  };
  by_blocks(n, vertex_bytes, [&](Id i) {
    put(mesh.points.data() + 3 * i, 12);
    for (const Field& f : mesh.point_fields)
      put(f.values.data() + i * f.components, 4 * static_cast<std::size_t>(f.components));
  });
  static_assert(sizeof(PointIndex) == 4, "ids are written as uint");
  // Each face's cell field values follow its ids (the face properties).
  std::size_t cell_bytes = 0;
  for (const Field& f : mesh.cell_fields) cell_bytes += 4 * static_cast<std::size_t>(f.components);
  auto put_cell_fields = [&](Id c) {
    for (const Field& f : mesh.cell_fields)
      put(f.values.data() + c * f.components, 4 * static_cast<std::size_t>(f.components));
  };
  if (mesh.offsets.empty() && !wide_count && cell_bytes <= kBlock / 16) {
    by_blocks(cells, 13 + cell_bytes, [&](Id c) {
      *at++ = 3;
      put(mesh.connectivity.data() + 3 * c, 12);
      put_cell_fields(c);
    });
  } else {
    for (Id c = 0; c < cells; ++c) {
      const std::uint64_t b = mesh.cell_begin(c), e = mesh.cell_end(c);
      const std::size_t ids = 4 * static_cast<std::size_t>(e - b), count = wide_count ? 4 : 1;
      const auto size = static_cast<std::uint32_t>(e - b);  // its low byte when not wide
      if (count + ids + cell_bytes > kBlock) {  // one huge record: its own writes
        room(kBlock);
        file.write(&size, count);
        file.write(mesh.connectivity.data() + b, ids);
        for (const Field& f : mesh.cell_fields)
          file.write(f.values.data() + c * f.components, 4 * static_cast<std::size_t>(f.components));
        continue;
      }
      room(count + ids + cell_bytes);
      put(&size, count);
      put(mesh.connectivity.data() + b, ids);
      put_cell_fields(c);
    }
  }
  file.write(block.get(), static_cast<std::size_t>(at - block.get()));
  return true;
}

}  // namespace

void write_ply(const SurfaceMesh& mesh, const std::string& path) {
  validate_mesh(mesh, path);
  const Id n = mesh.num_points();
  const Id cells = mesh.num_cells();
  std::uint64_t max_cell = 0;
  for (Id c = 0; c < cells; ++c) max_cell = std::max(max_cell, mesh.cell_end(c) - mesh.cell_begin(c));
  const bool wide_count = max_cell > 255;

  std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by keymesh\n";
  header += "element vertex " + std::to_string(n) + "\n";
  header += vertex_properties(mesh);
  header += "element face " + std::to_string(cells) + "\n";
  header += wide_count ? "property list uint uint vertex_indices\n" : "property list uchar uint vertex_indices\n";
  header += field_properties(mesh.cell_fields, {"vertex_indices"}, false);
  header += "end_header\n";

  AtomicFile file(path);
  file.write(header);
  if (std::endian::native == std::endian::little && write_ply_records(mesh, wide_count, file)) {
    file.commit();
    return;
  }
  std::string buf;
  constexpr std::size_t kFlush = 1 << 20;
  for (Id i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) append_le(buf, mesh.points[3 * i + a]);
    for (const Field& f : mesh.point_fields)
      for (int k = 0; k < f.components; ++k) append_le(buf, f.values[i * f.components + k]);
    if (buf.size() >= kFlush) {
      file.write(buf);
      buf.clear();
    }
  }
  for (Id c = 0; c < cells; ++c) {
    const std::uint64_t b = mesh.cell_begin(c), e = mesh.cell_end(c);
    if (wide_count) append_le(buf, static_cast<std::uint32_t>(e - b));
    else append_le(buf, static_cast<std::uint8_t>(e - b));
    for (std::uint64_t k = b; k < e; ++k) append_le(buf, static_cast<std::uint32_t>(mesh.connectivity[k]));
    for (const Field& f : mesh.cell_fields)
      for (int k = 0; k < f.components; ++k) append_le(buf, f.values[c * f.components + k]);
    if (buf.size() >= kFlush) {
      file.write(buf);
      buf.clear();
    }
  }
  file.write(buf);
  file.commit();
}

}  // namespace keymesh::io
