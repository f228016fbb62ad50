#include "mesh_formats.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "keymesh/core/error.hpp"
#include "mesh_bytes.hpp"
#include "vtk_xml.hpp"
#include "vtk_xml_writer.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::io {

using namespace mesh_bytes;
using namespace vtk_xml;

namespace {

// Calls f(T{}) with the C++ type of the file's scalar type s.
template <class F>
decltype(auto) with_type(ScalarType s, F&& f) {
  switch (s) {
    case ScalarType::Int8: return f(std::int8_t{});
    case ScalarType::UInt8: return f(std::uint8_t{});
    case ScalarType::Int16: return f(std::int16_t{});
    case ScalarType::UInt16: return f(std::uint16_t{});
    case ScalarType::Int32: return f(std::int32_t{});
    case ScalarType::UInt32: return f(std::uint32_t{});
    case ScalarType::Int64: return f(std::int64_t{});
    case ScalarType::UInt64: return f(std::uint64_t{});
    case ScalarType::Float32: return f(float{});
    case ScalarType::Float64: return f(double{});
  }
  return f(double{});
}

// A decoded array, or a view of the file's own bytes when the array is
// appended raw and uncompressed (the connectivity of 82.9 M tets is 1.3 GB
// that need not be copied before they are converted).
struct Values {
  ScalarType type = ScalarType::Float64;
  bool big = false;
  int components = 1;
  std::string_view bytes;
  std::unique_ptr<Array> owned;  // heap-held, so `bytes` survives moves
  std::size_t count() const { return bytes.size() / scalar_size(type); }
  const char* at(std::size_t i) const { return bytes.data() + i * scalar_size(type); }
};

Values get_array(const XmlNode& node, const Context& ctx, const std::string& what, std::int64_t expected) {
  const std::string* format = node.attr("format");
  const std::string* type_attr = node.attr("type");
  const std::string* offset_attr = node.attr("offset");
  const std::string* comps_attr = node.attr("NumberOfComponents");
  ScalarType type = ScalarType::Float64;
  bool known_type = false;
  if (type_attr)
    if (const auto t = vtk_scalar(*type_attr)) type = *t, known_type = true;
  std::int64_t offset = -1, comps = 1;
  if (format && *format == "appended" && ctx.appended_encoding == "raw" && ctx.compressor.empty() && known_type &&
      offset_attr && parse_int64(*offset_attr, offset) && offset >= 0 &&
      (!comps_attr || (parse_int64(*comps_attr, comps) && comps >= 1 && comps <= 4096))) {
    const std::size_t hs = scalar_size(ctx.header);
    const std::uint64_t left = ctx.appended.size();
    if (std::uint64_t(offset) <= left && left - std::uint64_t(offset) >= hs) {
      const char* h = ctx.appended.data() + offset;
      const std::uint64_t n = ctx.header == ScalarType::UInt64 ? load<std::uint64_t>(h, ctx.big_endian)
                                                           : load<std::uint32_t>(h, ctx.big_endian);
      const std::uint64_t size = scalar_size(type);
      if (n <= left - std::uint64_t(offset) - hs && n % size == 0 &&
          (expected < 0 || n / size == std::uint64_t(expected))) {
        Values v{type, ctx.big_endian, static_cast<int>(comps), ctx.appended.substr(std::size_t(offset) + hs, n), {}};
        return v;
      }
    }
  }
  // Anything else, and every malformed case (for its message), goes through the shared decoder.
  Values v;
  v.owned = std::make_unique<Array>(decode_array(node, ctx, what, expected));
  v.type = v.owned->type;
  v.big = v.owned->big;
  v.components = v.owned->components;
  v.bytes = v.owned->bytes;
  return v;
}

// Appends the values of `a`, converted to float, to out (in parallel: the
// points of 256^3 are 50 M values).
void append_floats(const Values& a, keymesh::Array<float>& out) {
  const std::size_t at = out.size();
  out.resize(at + a.count());
  float* dst = out.data() + at;
  with_type(a.type, [&](auto tag) {
    using T = decltype(tag);
    const char* src = a.bytes.data();
    const bool big = a.big;
    parallel::for_each(static_cast<Id>(a.count()),
                       [&](Id i) { dst[i] = static_cast<float>(load<T>(src + std::size_t(i) * sizeof(T), big)); });
  });
}

// dst[i] = base + a[i] for every value of `a`, each required to be an
// integer in [0, limit). Returns the index of the first value that is not,
// or a.count() when all are.
template <class D>
std::size_t convert_ints(const Values& a, std::uint64_t limit, std::uint64_t base, D* dst) {
  const Id n = static_cast<Id>(a.count());
  const int chunks = parallel::chunk_count(n, 1 << 16);
  std::vector<Id> first_bad(static_cast<std::size_t>(std::max(chunks, 1)), n);
  with_type(a.type, [&](auto tag) {
    using T = decltype(tag);
    const char* src = a.bytes.data();
    const bool big = a.big;
    parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
      for (Id i = b; i < e; ++i) {
        const T v = load<T>(src + std::size_t(i) * sizeof(T), big);
        std::uint64_t u = 0;
        if constexpr (std::is_floating_point_v<T>) {
          // Old writers store ids as floats: only exact integers pass.
          if (!(v >= T(0) && v < static_cast<T>(limit)) || v != std::floor(v)) {
            first_bad[std::size_t(c)] = i;
            return;
          }
          u = static_cast<std::uint64_t>(v);
        } else {
          if constexpr (std::is_signed_v<T>) {
            if (v < 0) {
              first_bad[std::size_t(c)] = i;
              return;
            }
          }
          u = static_cast<std::uint64_t>(v);
        }
        if (u >= limit) {
          first_bad[std::size_t(c)] = i;
          return;
        }
        dst[i] = static_cast<D>(base + u);
      }
    });
  });
  return static_cast<std::size_t>(*std::min_element(first_bad.begin(), first_bad.end()));
}

std::string value_text(const Values& a, std::size_t i) {
  std::int64_t v = 0;
  if (load_as_int64(a.at(i), a.type, a.big, v)) return std::to_string(v);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", load_as_double(a.at(i), a.type, a.big));
  return buf;
}

// Every numeric array of a PointData / CellData section with `tuples` tuples.
std::vector<Field> read_fields(const XmlNode* section, const Context& ctx, std::int64_t tuples, const char* what) {
  std::vector<Field> fields;
  if (!section || tuples == 0) return fields;
  for (const auto& c : section->children) {
    if (c->name != "DataArray") continue;
    const std::string* t = c->attr("type");
    if (!t || !vtk_scalar(*t)) continue;  // String arrays and the like are not fields
    const std::string* name = c->attr("Name");
    const std::string label = std::string(what) + " array";
    const Values a = get_array(*c, ctx, label, -1);
    if (a.count() != static_cast<std::uint64_t>(tuples) * static_cast<std::uint64_t>(a.components))
      throw InputError(ctx.path + ": " + label + " '" + (name ? *name : std::string()) + "' holds " +
                       std::to_string(a.count()) + " values for " + std::to_string(tuples) + " tuples x " +
                       std::to_string(a.components) + " components");
    Field f{name ? *name : std::string("array"), a.components, {}};
    append_floats(a, f.values);
    fields.push_back(std::move(f));
  }
  if (const std::string* marked = section->attr("Normals"); marked && *marked != "Normals") {
    bool taken = false;
    for (const Field& f : fields) taken = taken || f.name == "Normals";
    for (Field& f : fields)
      if (!taken && f.name == *marked && f.components == 3) f.name = "Normals";
  }
  return fields;
}

// Adds the fields of one piece to those kept so far. The first piece that
// has tuples sets the list; later pieces keep only the fields they share
// (same name and components). Pieces without tuples change nothing.
void merge_fields(std::vector<Field>& kept, bool& started, std::vector<Field>&& piece, std::int64_t tuples) {
  if (tuples == 0) return;
  if (!started) {
    kept = std::move(piece);
    started = true;
    return;
  }
  std::vector<Field> out;
  for (Field& f : kept)
    for (Field& g : piece)
      if (g.name == f.name && g.components == f.components) {
        f.values.insert(f.values.end(), g.values.begin(), g.values.end());
        out.push_back(std::move(f));
        break;
      }
  kept = std::move(out);
}

// Calls f(Array<uint32_t or uint64_t>&), the storage of the array's width.
template <class F>
void with_storage(IndexArray& a, F&& f) {
  if (a.wide()) f(a.wide_values());
  else f(a.narrow());
}

}  // namespace

UnstructuredGrid read_vtu(const std::string& path) { return parse_vtu(read_whole_file(path), path); }

namespace {

// The <Piece>s and the points they declare in all (bounded before any
// allocation depends on it).
std::vector<const XmlNode*> list_pieces(const XmlNode& ug, const std::string& path, std::int64_t& total_points) {
  std::vector<const XmlNode*> pieces;
  total_points = 0;
  for (const auto& p : ug.children)
    if (p->name == "Piece") {
      pieces.push_back(p.get());
      total_points += count_attr(*p, "NumberOfPoints", path);
      if (total_points > (std::int64_t{1} << 48)) throw InputError(path + ": the pieces declare too many points");
    }
  if (pieces.empty()) throw InputError(path + ": <UnstructuredGrid> has no <Piece>");
  return pieces;
}

// The cells of every piece read so far: end offsets (from 0) and VTK types.
struct CellLists {
  std::vector<std::uint64_t> offsets{0};
  std::vector<std::uint8_t> types;
};

// A piece's offsets, shifted by the ids of the pieces before it (id_base),
// non-decreasing.
void append_offsets(const Values& o, std::uint64_t id_base, const std::string& path, const std::string& where,
                    std::vector<std::uint64_t>& offsets) {
  const std::size_t at = offsets.size();
  offsets.resize(at + o.count());
  const std::size_t bad = convert_ints(o, std::uint64_t{1} << 62, id_base, offsets.data() + at);
  if (bad < o.count())
    throw InputError(path + ": cell offset " + value_text(o, bad) + " of cell " + std::to_string(bad) + where +
                     " is not a valid offset");
  for (std::size_t k = at; k < offsets.size(); ++k)
    if (offsets[k] < offsets[k - 1])
      throw InputError(path + ": cell offsets" + where + " decrease at cell " + std::to_string(k - at));
}

void append_types(const Values& t, const std::string& path, const std::string& where,
                  std::vector<std::uint8_t>& types) {
  const std::size_t at = types.size();
  types.resize(at + t.count());
  if (const std::size_t bad = convert_ints(t, 256, 0, types.data() + at); bad < t.count())
    throw InputError(path + ": cell " + std::to_string(bad) + where + " has cell type " + value_text(t, bad));
}

// A piece's <Cells>: offsets, types, then its connectivity (ids in range of
// the piece's npts points, offset by base) straight into g.connectivity.
void read_piece_cells(const XmlNode& piece, const Context& ctx, const std::string& where, std::int64_t ncells,
                      std::int64_t npts, std::uint64_t base, UnstructuredGrid& g, CellLists& lists) {
  const std::string& path = ctx.path;
  const XmlNode* cells = piece.child("Cells");
  const XmlNode* conn = named_array(cells, "connectivity");
  const XmlNode* offs = named_array(cells, "offsets");
  const XmlNode* typ = named_array(cells, "types");
  if (!conn || !offs || !typ)
    throw InputError(path + ": <Cells>" + where + " lacks its connectivity, offsets or types array");
  const std::uint64_t id_base = g.connectivity.size();
  append_offsets(get_array(*offs, ctx, "Cells offsets array" + where, ncells), id_base, path, where, lists.offsets);
  append_types(get_array(*typ, ctx, "Cells types array" + where, ncells), path, where, lists.types);
  const Values c = get_array(*conn, ctx, "Cells connectivity array" + where, -1);
  if (lists.offsets.back() - id_base != c.count())
    throw InputError(path + ": cell offsets" + where + " end at " + std::to_string(lists.offsets.back() - id_base) +
                     " but the connectivity holds " + std::to_string(c.count()) + " ids");
  with_storage(g.connectivity, [&](auto& ids) {
    ids.resize(ids.size() + c.count());
    const std::size_t bad = convert_ints(c, static_cast<std::uint64_t>(npts), base, ids.data() + id_base);
    if (bad < c.count())
      throw InputError(path + ": cell connectivity" + where + " refers to point " + value_text(c, bad) +
                       " at connectivity[" + std::to_string(bad) + "], out of range (" + std::to_string(npts) +
                       " points)");
  });
}

// One fixed-size type throughout: stored uniformly (no offsets or types).
void adopt_cell_lists(CellLists& lists, UnstructuredGrid& g) {
  const std::vector<std::uint8_t>& types = lists.types;
  const bool one_type = !types.empty() && std::all_of(types.begin(), types.end(), [&](std::uint8_t t) {
    return t == types.front();
  });
  const int k = one_type ? cell_type_size(static_cast<CellType>(types.front())) : 0;
  bool uniform = one_type && k > 0;
  for (std::size_t c = 0; uniform && c + 1 < lists.offsets.size(); ++c)
    uniform = lists.offsets[c + 1] - lists.offsets[c] == std::uint64_t(k);
  if (uniform) {
    g.uniform_type = static_cast<CellType>(types.front());
  } else if (!types.empty()) {
    g.offsets = std::move(lists.offsets);
    g.cell_types = std::move(lists.types);
  }
}

}  // namespace

UnstructuredGrid parse_vtu(std::string_view data, const std::string& path) {
  ParsedXml xml = parse_xml(data, path);
  const Context ctx = file_context(xml, path, "UnstructuredGrid");
  const XmlNode* ug = xml.root->child("UnstructuredGrid");
  if (!ug) throw InputError(path + ": VTK file has no <UnstructuredGrid>");
  std::int64_t total_points = 0;
  const std::vector<const XmlNode*> pieces = list_pieces(*ug, path, total_points);
  // Ids go straight into an IndexArray of the width the total point count
  // needs: one copy from the decoded bytes, none through 64-bit temporaries.
  UnstructuredGrid g;
  g.connectivity = IndexArray::for_ids(static_cast<std::uint64_t>(total_points), 0);
  CellLists lists;
  bool point_fields_started = false, cell_fields_started = false;
  for (std::size_t pi = 0; pi < pieces.size(); ++pi) {
    const XmlNode& piece = *pieces[pi];
    const std::string where = pieces.size() > 1 ? " (piece " + std::to_string(pi) + ")" : std::string();
    const std::int64_t npts = count_attr(piece, "NumberOfPoints", path);
    const std::int64_t ncells = count_attr(piece, "NumberOfCells", path);
    const std::uint64_t base = g.points.size() / 3;
    if (npts > 0) {
      const XmlNode* pts = piece.child("Points");
      const XmlNode* arr = pts ? pts->child("DataArray") : nullptr;
      if (!arr) throw InputError(path + ": piece with " + std::to_string(npts) + " points has no <Points> array");
      append_floats(get_array(*arr, ctx, "Points array" + where, 3 * npts), g.points);
    }
    if (ncells > 0) read_piece_cells(piece, ctx, where, ncells, npts, base, g, lists);
    merge_fields(g.point_fields, point_fields_started, read_fields(piece.child("PointData"), ctx, npts, "PointData"),
                 npts);
    merge_fields(g.cell_fields, cell_fields_started, read_fields(piece.child("CellData"), ctx, ncells, "CellData"),
                 ncells);
  }
  adopt_cell_lists(lists, g);
  g.validate(path, /*check_ids=*/false);  // every id was checked as it was read
  return g;
}

namespace {

// A <PointData> or <CellData> section and its fields' arrays.
std::string data_section(vtk_xml::AppendedArrays& arrays, const char* tag, const std::vector<Field>& fields) {
  std::string x = std::string("      <") + tag + vtk_xml::field_attributes(fields) + ">\n";
  for (const Field& f : fields) x += arrays.floats(f.name, f.components, f.values);
  return x + "      </" + tag + ">\n";
}

// The <Cells> section: connectivity and offsets as Int32 whenever every value
// fits (whatever the in-memory width), Int64 beyond; a UInt8 type per cell.
std::string cells_section(vtk_xml::AppendedArrays& arrays, const UnstructuredGrid& g) {
  constexpr std::uint64_t int32_max = std::uint64_t(std::numeric_limits<std::int32_t>::max());
  const Id cells = g.num_cells();
  const ScalarType id_type = std::uint64_t(g.num_points()) > int32_max + 1 ? ScalarType::Int64 : ScalarType::Int32;
  const ScalarType offset_type = g.connectivity.size() > int32_max ? ScalarType::Int64 : ScalarType::Int32;
  std::string x = "      <Cells>\n";
  x += g.connectivity.visit([&](auto ids) {
    using T = typename decltype(ids)::value_type;
    // Ids already as wide as the file's are written as they are.
    if (sizeof(T) == scalar_size(id_type))
      return arrays.bytes(id_type, "connectivity", 0, ids.data(), sizeof(T) * ids.size());
    return arrays.integers(id_type, "connectivity", ids.size(), [ids](std::uint64_t i) { return ids[i]; });
  });
  x += arrays.integers(offset_type, "offsets", std::uint64_t(cells),
                       [&g](std::uint64_t c) { return g.cell_end(static_cast<Id>(c)); });
  if (!g.cell_types.empty())
    x += arrays.bytes(ScalarType::UInt8, "types", 0, g.cell_types.data(), g.cell_types.size());
  else
    x += arrays.integers(ScalarType::UInt8, "types", std::uint64_t(cells), [&g](std::uint64_t) {
      return static_cast<std::uint8_t>(g.uniform_type);
    });
  return x + "      </Cells>\n";
}

}  // namespace

void write_vtu(const UnstructuredGrid& g, const std::string& path) {
  g.validate(path);
  vtk_xml::AppendedArrays arrays;
  std::string x = vtk_xml::file_header("UnstructuredGrid") + "  <UnstructuredGrid>\n";
  x += "    <Piece NumberOfPoints=\"" + std::to_string(g.num_points()) + "\" NumberOfCells=\"" +
       std::to_string(g.num_cells()) + "\">\n";
  x += data_section(arrays, "PointData", g.point_fields);
  x += data_section(arrays, "CellData", g.cell_fields);
  x += "      <Points>\n" + arrays.floats("Points", 3, g.points) + "      </Points>\n";
  x += cells_section(arrays, g);
  x += "    </Piece>\n  </UnstructuredGrid>\n";
  arrays.write(path, x);
}

}  // namespace keymesh::io
