#include "keymesh/io/ply.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "keymesh/io/mesh_bytes.hpp"

#include "checked_mesh.hpp"

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

std::optional<ScalarType> ply_scalar(std::string_view t) {
  if (t == "char" || t == "int8") return ScalarType::Int8;
  if (t == "uchar" || t == "uint8") return ScalarType::UInt8;
  if (t == "short" || t == "int16") return ScalarType::Int16;
  if (t == "ushort" || t == "uint16") return ScalarType::UInt16;
  if (t == "int" || t == "int32") return ScalarType::Int32;
  if (t == "uint" || t == "uint32") return ScalarType::UInt32;
  if (t == "float" || t == "float32") return ScalarType::Float32;
  if (t == "double" || t == "float64") return ScalarType::Float64;
  return std::nullopt;
}

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

 private:
  bool big() const { return format_ == Format::BinaryBig; }
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

// A vertex-element field read from one or more scalar properties.
struct FieldPlan {
  std::string name;
  std::vector<std::size_t> props;  // property indices, one per component
};

}  // namespace

SurfaceMesh parse_ply(std::string_view data, const std::string& path) {
  // ---- header ---------------------------------------------------------------
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
  std::optional<Format> format;
  std::vector<Element> elements;
  bool ended = false;
  while (next_line(line)) {
    const auto w = split_words(line);
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      ended = true;
      break;
    }
    if (w[0] == "format") {
      if (w.size() < 2) throw InputError(path + ": PLY format line without a format");
      if (w[1] == "ascii") format = Format::Ascii;
      else if (w[1] == "binary_little_endian") format = Format::BinaryLittle;
      else if (w[1] == "binary_big_endian") format = Format::BinaryBig;
      else throw InputError(path + ": unknown PLY format '" + std::string(w[1]) + "'");
    } else if (w[0] == "element") {
      std::int64_t count = 0;
      if (w.size() < 3 || !parse_int64(w[2], count) || count < 0)
        throw InputError(path + ": bad PLY element line '" + std::string(line.substr(0, 80)) + "'");
      elements.push_back({std::string(w[1]), static_cast<std::uint64_t>(count), {}});
    } else if (w[0] == "property") {
      if (elements.empty()) throw InputError(path + ": PLY property before any element");
      Property p;
      if (w.size() >= 5 && w[1] == "list") {
        const auto ct = ply_scalar(w[2]);
        const auto it = ply_scalar(w[3]);
        if (!ct || !it) throw InputError(path + ": unknown PLY type in '" + std::string(line.substr(0, 80)) + "'");
        if (scalar_is_float(*ct)) throw InputError(path + ": PLY list count type must be an integer type");
        p.is_list = true;
        p.count_type = *ct;
        p.type = *it;
        p.name = std::string(w[4]);
      } else if (w.size() >= 3) {
        const auto t = ply_scalar(w[1]);
        if (!t) throw InputError(path + ": unknown PLY type in '" + std::string(line.substr(0, 80)) + "'");
        p.type = *t;
        p.name = std::string(w[2]);
      } else {
        throw InputError(path + ": bad PLY property line '" + std::string(line.substr(0, 80)) + "'");
      }
      elements.back().props.push_back(std::move(p));
    } else {
      throw InputError(path + ": unknown PLY header line '" + std::string(line.substr(0, 80)) + "'");
    }
  }
  if (!ended) throw InputError(path + ": truncated PLY header (no end_header)");
  if (!format) throw InputError(path + ": PLY header has no format line");

  // ---- plan -------------------------------------------------------------------
  const Element* vertex = nullptr;
  for (const auto& e : elements)
    if (e.name == "vertex") vertex = &e;
  const std::uint64_t num_points = vertex ? vertex->count : 0;

  SurfaceMesh mesh;
  ValueReader in(data.substr(pos), *format, path);
  const bool ascii = *format == Format::Ascii;
  bool have_faces = false;

  for (const Element& e : elements) {
    if (e.count == 0) continue;
    if (e.props.empty()) continue;  // nothing stored per record
    // Refuse counts the rest of the file cannot hold before allocating anything.
    std::uint64_t min_record = 0;
    for (const auto& p : e.props) min_record += ascii ? 2 : scalar_size(p.is_list ? p.count_type : p.type);
    if (e.count > (in.remaining() + 1) / min_record)
      throw InputError(path + ": element '" + e.name + "' declares " + std::to_string(e.count) +
                       " records, more than the file can hold");
    const std::string what = "element '" + e.name + "'";

    if (&e == vertex) {
      if (e.count > std::numeric_limits<PointIndex>::max())
        throw LimitError(path + ": " + std::to_string(e.count) + " vertices exceed 2^32 - 1");
      std::optional<std::size_t> px, py, pz, pnx, pny, pnz;
      for (std::size_t i = 0; i < e.props.size(); ++i) {
        const auto& p = e.props[i];
        if (p.is_list) continue;
        if (p.name == "x") px = i;
        else if (p.name == "y") py = i;
        else if (p.name == "z") pz = i;
        else if (p.name == "nx") pnx = i;
        else if (p.name == "ny") pny = i;
        else if (p.name == "nz") pnz = i;
      }
      if (!px || !py || !pz) throw InputError(path + ": PLY vertex element lacks x, y or z");
      const bool normals = pnx && pny && pnz;
      std::vector<FieldPlan> plans;
      if (normals) plans.push_back({"Normals", {*pnx, *pny, *pnz}});
      // Group p_0, p_1, ... runs (as keymesh writes multi-component fields).
      for (std::size_t i = 0; i < e.props.size();) {
        const auto& p = e.props[i];
        if (p.is_list || i == *px || i == *py || i == *pz ||
            (normals && (i == *pnx || i == *pny || i == *pnz))) {
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
      // Where each property goes: slot 0..2 = xyz, then field component slots.
      std::vector<int> target(e.props.size(), -1);
      target[*px] = 0;
      target[*py] = 1;
      target[*pz] = 2;
      std::vector<std::pair<std::size_t, std::size_t>> field_slot(e.props.size(), {SIZE_MAX, 0});
      for (std::size_t f = 0; f < plans.size(); ++f)
        for (std::size_t k = 0; k < plans[f].props.size(); ++k) field_slot[plans[f].props[k]] = {f, k};
      mesh.points.resize(3 * e.count);
      mesh.point_fields.resize(plans.size());
      for (std::size_t f = 0; f < plans.size(); ++f) {
        mesh.point_fields[f].name = plans[f].name;
        mesh.point_fields[f].components = static_cast<int>(plans[f].props.size());
        mesh.point_fields[f].values.resize(e.count * plans[f].props.size());
      }
      for (std::uint64_t r = 0; r < e.count; ++r) {
        for (std::size_t i = 0; i < e.props.size(); ++i) {
          const auto& p = e.props[i];
          if (p.is_list) {
            in.skip(p, what);
          } else if (target[i] >= 0) {
            mesh.points[3 * r + target[i]] = static_cast<float>(in.read_double(p.type, what));
          } else {
            const auto [f, k] = field_slot[i];
            Field& fd = mesh.point_fields[f];
            fd.values[r * fd.components + k] = static_cast<float>(in.read_double(p.type, what));
          }
        }
      }
    } else if (e.name == "face" && !have_faces) {
      std::optional<std::size_t> plist;
      for (std::size_t i = 0; i < e.props.size(); ++i)
        if (e.props[i].is_list && (e.props[i].name == "vertex_indices" || e.props[i].name == "vertex_index"))
          plist = i;
      if (!plist) throw InputError(path + ": PLY face element has no vertex_indices list");
      if (scalar_is_float(e.props[*plist].type)) throw InputError(path + ": PLY vertex_indices must be integers");
      have_faces = true;
      mesh.offsets.reserve(e.count + 1);
      mesh.offsets.push_back(0);
      mesh.connectivity.reserve(3 * e.count);
      for (std::uint64_t r = 0; r < e.count; ++r) {
        for (std::size_t i = 0; i < e.props.size(); ++i) {
          const auto& p = e.props[i];
          if (i != *plist) {
            in.skip(p, what);
            continue;
          }
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
      }
    } else {
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
  // Every vertex property once: a field whose PLY name is taken (a field
  // named x, nx, or one named like another's component) is written as
  // field_<name> (field_<name>_2, ... while that is taken too).
  std::set<std::string> taken{"x", "y", "z"};
  const bool normals = std::any_of(mesh.point_fields.begin(), mesh.point_fields.end(),
                                   [](const Field& f) { return f.name == "Normals" && f.components == 3; });
  if (normals) taken.insert({"nx", "ny", "nz"});
  auto properties = [](const std::string& base, int components) {
    std::vector<std::string> names;
    if (components == 1) names.push_back(base);
    else
      for (int k = 0; k < components; ++k) names.push_back(base + "_" + std::to_string(k));
    return names;
  };
  header += "property float x\nproperty float y\nproperty float z\n";
  bool normals_written = false;
  for (const Field& f : mesh.point_fields) {
    if (f.name == "Normals" && f.components == 3 && !normals_written) {
      header += "property float nx\nproperty float ny\nproperty float nz\n";
      normals_written = true;
      continue;
    }
    std::string base = ply_name(f.name);
    auto names = properties(base, f.components);
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
      names = properties(renamed, f.components);
    }
    for (const std::string& name : names) {
      taken.insert(name);
      header += "property float ";
      header += name;
      header += '\n';
    }
  }
  header += "element face " + std::to_string(cells) + "\n";
  header += wide_count ? "property list uint uint vertex_indices\n" : "property list uchar uint vertex_indices\n";
  header += "end_header\n";

  AtomicFile file(path);
  file.write(header);
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
    if (buf.size() >= kFlush) {
      file.write(buf);
      buf.clear();
    }
  }
  file.write(buf);
  file.commit();
}

}  // namespace keymesh::io
