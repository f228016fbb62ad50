#include "keymesh/io/vtu.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "keymesh/io/mesh_bytes.hpp"
#include "keymesh/io/vtk_xml.hpp"

namespace keymesh::io {

using namespace mesh_bytes;
using namespace vtk_xml;

namespace {

// Every numeric array of a PointData / CellData section with `tuples` tuples.
std::vector<Field> read_fields(const XmlNode* section, const Context& ctx, std::int64_t tuples, const char* what) {
  std::vector<Field> fields;
  if (!section || tuples == 0) return fields;
  for (const auto& c : section->children) {
    if (c->name != "DataArray") continue;
    const std::string* t = c->attr("type");
    if (!t || !vtk_scalar(*t)) continue;
    const std::string* name = c->attr("Name");
    const std::string label = std::string(what) + " array '" + (name ? *name : std::string()) + "'";
    Array a = decode_array(*c, ctx, label, -1);
    if (a.count() != static_cast<std::uint64_t>(tuples) * static_cast<std::uint64_t>(a.components))
      throw InputError(ctx.path + ": " + label + " holds " + std::to_string(a.count()) + " values for " +
                       std::to_string(tuples) + " tuples x " + std::to_string(a.components) + " components");
    Field f{name ? *name : std::string("array"), a.components, std::vector<float>(a.count())};
    for (std::size_t i = 0; i < a.count(); ++i) f.values[i] = static_cast<float>(a.as_double(i));
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

// Appends the fields of a later piece to those kept so far: only fields
// present (same name and components) in every piece survive.
void merge_fields(std::vector<Field>& kept, std::vector<Field>&& piece, bool first) {
  if (first) {
    kept = std::move(piece);
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

}  // namespace

UnstructuredGrid read_vtu(const std::string& path) { return parse_vtu(read_whole_file(path), path); }

UnstructuredGrid parse_vtu(std::string_view data, const std::string& path) {
  ParsedXml xml = parse_xml(data, path);
  const Context ctx = file_context(xml, path, "UnstructuredGrid");
  const XmlNode* ug = xml.root->child("UnstructuredGrid");
  if (!ug) throw InputError(path + ": VTK file has no <UnstructuredGrid>");

  // Ids are gathered 64-bit, then narrowed once the point count is known.
  std::vector<std::uint64_t> ids, offsets{0};
  std::vector<std::uint8_t> types;
  UnstructuredGrid g;
  bool first = true;
  for (const auto& piece_ptr : ug->children) {
    if (piece_ptr->name != "Piece") continue;
    const XmlNode& piece = *piece_ptr;
    const std::int64_t npts = count_attr(piece, "NumberOfPoints", path);
    const std::int64_t ncells = count_attr(piece, "NumberOfCells", path);
    const std::uint64_t base = g.points.size() / 3;
    if (npts > 0) {
      const XmlNode* pts = piece.child("Points");
      const XmlNode* arr = pts ? pts->child("DataArray") : nullptr;
      if (!arr) throw InputError(path + ": piece with " + std::to_string(npts) + " points has no <Points> array");
      const Array a = decode_array(*arr, ctx, "Points array", 3 * npts);
      g.points.reserve(g.points.size() + a.count());
      for (std::size_t i = 0; i < a.count(); ++i) g.points.push_back(static_cast<float>(a.as_double(i)));
    }
    if (ncells > 0) {
      const XmlNode* cells = piece.child("Cells");
      const XmlNode* conn = named_array(cells, "connectivity");
      const XmlNode* offs = named_array(cells, "offsets");
      const XmlNode* typ = named_array(cells, "types");
      if (!conn || !offs || !typ)
        throw InputError(path + ": <Cells> lacks its connectivity, offsets or types array");
      const Array o = decode_array(*offs, ctx, "Cells offsets array", ncells);
      const Array t = decode_array(*typ, ctx, "Cells types array", ncells);
      const Array c = decode_array(*conn, ctx, "Cells connectivity array", -1);
      const std::uint64_t id_base = ids.size();
      std::uint64_t prev = 0;
      for (std::size_t k = 0; k < o.count(); ++k) {
        std::int64_t v = 0;
        if (!o.as_int(k, v) || v < 0 || static_cast<std::uint64_t>(v) < prev)
          throw InputError(path + ": cell offsets are not non-decreasing at cell " + std::to_string(k));
        prev = static_cast<std::uint64_t>(v);
        offsets.push_back(id_base + prev);
      }
      if (prev != c.count())
        throw InputError(path + ": cell offsets end at " + std::to_string(prev) + " but connectivity holds " +
                         std::to_string(c.count()) + " ids");
      ids.reserve(ids.size() + c.count());
      for (std::size_t k = 0; k < c.count(); ++k) {
        std::int64_t v = 0;
        if (!c.as_int(k, v) || v < 0 || v >= npts)
          throw InputError(path + ": cell connectivity refers to point " + std::to_string(v) + " out of range (" +
                           std::to_string(npts) + " points in the piece)");
        ids.push_back(base + static_cast<std::uint64_t>(v));
      }
      for (std::size_t k = 0; k < t.count(); ++k) {
        std::int64_t v = 0;
        if (!t.as_int(k, v) || v < 0 || v > 255)
          throw InputError(path + ": cell " + std::to_string(k) + " has cell type " + std::to_string(v));
        types.push_back(static_cast<std::uint8_t>(v));
      }
    }
    merge_fields(g.point_fields, read_fields(piece.child("PointData"), ctx, npts, "PointData"), first || npts == 0);
    merge_fields(g.cell_fields, read_fields(piece.child("CellData"), ctx, ncells, "CellData"), first || ncells == 0);
    first = false;
  }
  g.connectivity = IndexArray::for_ids(g.points.size() / 3, ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) g.connectivity.set(k, ids[k]);
  ids = {};
  // One fixed-size type throughout: store it uniformly (no offsets or types).
  const bool one_type = !types.empty() && std::all_of(types.begin(), types.end(), [&](std::uint8_t t) {
    return t == types.front();
  });
  const int k = one_type ? cell_type_size(static_cast<CellType>(types.front())) : 0;
  bool uniform = one_type && k > 0;
  for (std::size_t c = 0; uniform && c + 1 < offsets.size(); ++c) uniform = offsets[c + 1] - offsets[c] == std::uint64_t(k);
  if (uniform) {
    g.uniform_type = static_cast<CellType>(types.front());
  } else if (!types.empty()) {
    g.offsets = std::move(offsets);
    g.cell_types = std::move(types);
  }
  g.validate(path);
  return g;
}

void write_vtu(const UnstructuredGrid& g, const std::string& path) {
  g.validate(path);
  const Id n = g.num_points();
  const Id cells = g.num_cells();
  const bool wide_ids = g.connectivity.wide();
  const std::uint64_t id_bytes = wide_ids ? 8 : 4;
  const bool wide_offsets = g.connectivity.size() > std::uint64_t(std::numeric_limits<std::int32_t>::max());
  const std::uint64_t offset_bytes = wide_offsets ? 8 : 4;
  auto first_scalar = [](const std::vector<Field>& fields) -> const Field* {
    for (const Field& f : fields)
      if (f.components == 1) return &f;
    return nullptr;
  };
  std::uint64_t offset = 0;
  auto block = [&](std::uint64_t bytes) {
    const std::uint64_t at = offset;
    offset += 8 + bytes;
    return std::to_string(at);
  };
  auto data_section = [&](const char* tag, const std::vector<Field>& fields) {
    std::string x = std::string("      <") + tag;
    if (const Field* s = first_scalar(fields)) x += " Scalars=\"" + xml_escape(s->name) + "\"";
    for (const Field& f : fields)
      if (f.name == "Normals" && f.components == 3) x += " Normals=\"Normals\"";
    x += ">\n";
    for (const Field& f : fields)
      x += "        <DataArray type=\"Float32\" Name=\"" + xml_escape(f.name) + "\" NumberOfComponents=\"" +
           std::to_string(f.components) + "\" format=\"appended\" offset=\"" + block(4 * f.values.size()) + "\"/>\n";
    return x + "      </" + tag + ">\n";
  };
  std::string x = "<?xml version=\"1.0\"?>\n";
  x += "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
  x += "  <UnstructuredGrid>\n";
  x += "    <Piece NumberOfPoints=\"" + std::to_string(n) + "\" NumberOfCells=\"" + std::to_string(cells) + "\">\n";
  x += data_section("PointData", g.point_fields);
  x += data_section("CellData", g.cell_fields);
  x += "      <Points>\n";
  x += "        <DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" offset=\"" +
       block(4 * g.points.size()) + "\"/>\n";
  x += "      </Points>\n";
  x += "      <Cells>\n";
  x += std::string("        <DataArray type=\"") + (wide_ids ? "Int64" : "Int32") +
       "\" Name=\"connectivity\" format=\"appended\" offset=\"" + block(id_bytes * g.connectivity.size()) + "\"/>\n";
  x += std::string("        <DataArray type=\"") + (wide_offsets ? "Int64" : "Int32") +
       "\" Name=\"offsets\" format=\"appended\" offset=\"" + block(offset_bytes * std::uint64_t(cells)) + "\"/>\n";
  x += "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"" + block(std::uint64_t(cells)) +
       "\"/>\n";
  x += "      </Cells>\n";
  x += "    </Piece>\n";
  x += "  </UnstructuredGrid>\n";
  x += "  <AppendedData encoding=\"raw\">\n   _";

  AtomicFile file(path);
  file.write(x);
  std::string buf;
  auto flush = [&](bool force) {
    if (force || buf.size() >= (1 << 20)) {
      file.write(buf);
      buf.clear();
    }
  };
  constexpr bool little = std::endian::native == std::endian::little;
  auto write_floats = [&](const std::vector<float>& v) {
    append_le(buf, static_cast<std::uint64_t>(4 * v.size()));
    flush(true);
    if constexpr (little) {
      file.write(v.data(), 4 * v.size());
    } else {
      for (float f : v) {
        append_le(buf, f);
        flush(false);
      }
    }
  };
  for (const Field& f : g.point_fields) write_floats(f.values);
  for (const Field& f : g.cell_fields) write_floats(f.values);
  write_floats(g.points);
  append_le(buf, static_cast<std::uint64_t>(id_bytes * g.connectivity.size()));
  flush(true);
  if (little && !wide_ids) {
    file.write(g.connectivity.narrow().data(), 4 * g.connectivity.size());
  } else if (little) {
    file.write(g.connectivity.wide_values().data(), 8 * g.connectivity.size());
  } else {
    for (std::size_t i = 0; i < g.connectivity.size(); ++i) {
      if (wide_ids) append_le(buf, static_cast<std::int64_t>(g.connectivity[i]));
      else append_le(buf, static_cast<std::int32_t>(g.connectivity[i]));
      flush(false);
    }
  }
  append_le(buf, static_cast<std::uint64_t>(offset_bytes * std::uint64_t(cells)));
  for (Id c = 0; c < cells; ++c) {
    if (wide_offsets) append_le(buf, static_cast<std::int64_t>(g.cell_end(c)));
    else append_le(buf, static_cast<std::int32_t>(g.cell_end(c)));
    flush(false);
  }
  append_le(buf, static_cast<std::uint64_t>(cells));
  for (Id c = 0; c < cells; ++c) {
    buf.push_back(static_cast<char>(g.cell_type(c)));
    flush(false);
  }
  buf += "\n  </AppendedData>\n</VTKFile>\n";
  flush(true);
  file.commit();
}

}  // namespace keymesh::io
