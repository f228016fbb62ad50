#include "mesh_formats.hpp"

#include <algorithm>
#include <bit>
#include <filesystem>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "mesh_bytes.hpp"
#include "vtk_xml.hpp"

namespace keymesh::io {

using namespace mesh_bytes;
using namespace vtk_xml;

namespace {

// Cells of one section (Polys or Strips): (offsets, connectivity) with
// offsets as end positions, validated.
struct CellArrays {
  std::vector<std::uint64_t> ends;
  Array connectivity;
};

std::optional<CellArrays> read_cells(const XmlNode& piece, std::string_view section_name, std::int64_t count,
                                     const Context& ctx) {
  if (count == 0) return std::nullopt;
  const XmlNode* section = piece.child(section_name);
  const XmlNode* conn = named_array(section, "connectivity");
  const XmlNode* offs = named_array(section, "offsets");
  const std::string what(section_name);
  if (!conn || !offs) throw InputError(ctx.path + ": <" + what + "> lacks its connectivity or offsets array");
  CellArrays cells;
  const Array o = decode_array(*offs, ctx, what + " array", count);
  cells.connectivity = decode_array(*conn, ctx, what + " array", -1);
  cells.ends.resize(o.count());
  std::uint64_t prev = 0;
  for (std::size_t c = 0; c < o.count(); ++c) {
    std::int64_t v = 0;
    if (!o.as_int(c, v) || v < 0 || static_cast<std::uint64_t>(v) < prev)
      throw InputError(ctx.path + ": " + what + " offsets are not non-decreasing at cell " + std::to_string(c));
    cells.ends[c] = static_cast<std::uint64_t>(v);
    prev = cells.ends[c];
  }
  if (prev != cells.connectivity.count())
    throw InputError(ctx.path + ": " + what + " offsets end at " + std::to_string(prev) + " but connectivity holds " +
                     std::to_string(cells.connectivity.count()) + " ids");
  return cells;
}

}  // namespace

SurfaceMesh read_vtp(const std::string& path) {
  const std::string data = read_whole_file(path);
  return parse_vtp(data, path);
}

SurfaceMesh parse_vtp(std::string_view data, const std::string& path) { return parse_vtp(data, path, nullptr); }

SurfaceMesh parse_vtp(std::string_view data, const std::string& path, std::vector<std::int64_t>* global_ids) {
  if (global_ids) global_ids->clear();
  bool every_piece_has_ids = true;
  ParsedXml xml = parse_xml(data, path);
  const XmlNode& root = *xml.root;
  const Context ctx = file_context(xml, path, "PolyData");

  const XmlNode* poly = root.child("PolyData");
  if (!poly) throw InputError(path + ": VTK file has no <PolyData>");

  SurfaceMesh mesh;
  mesh.offsets.push_back(0);
  bool first_piece = true;
  for (const auto& piece_ptr : poly->children) {
    if (piece_ptr->name != "Piece") continue;
    const XmlNode& piece = *piece_ptr;
    const std::int64_t npts = count_attr(piece, "NumberOfPoints", path);
    const std::int64_t npolys = count_attr(piece, "NumberOfPolys", path);
    const std::int64_t nstrips = count_attr(piece, "NumberOfStrips", path);
    const std::uint64_t base = mesh.points.size() / 3;

    // Points: decode first, so a NumberOfPoints the data does not back is
    // refused before anything of that size is allocated.
    if (npts > 0) {
      const XmlNode* pts = piece.child("Points");
      const XmlNode* arr = pts ? pts->child("DataArray") : nullptr;
      if (!arr) throw InputError(path + ": piece with " + std::to_string(npts) + " points has no <Points> array");
      const Array a = decode_array(*arr, ctx, "Points array", 3 * npts);
      mesh.points.reserve(mesh.points.size() + a.count());
      for (std::size_t i = 0; i < a.count(); ++i) mesh.points.push_back(static_cast<float>(a.as_double(i)));
    }
    if (base + static_cast<std::uint64_t>(npts) > std::numeric_limits<PointIndex>::max())
      throw LimitError(path + ": more than 2^32 - 1 points");

    // Point data: every numeric array with one tuple per point.
    std::vector<Field> fields;
    bool piece_has_ids = false;
    if (const XmlNode* pd = piece.child("PointData"); pd && npts > 0) {
      const std::string* ids_name = pd->attr("GlobalIds");
      for (const auto& c : pd->children) {
        if (c->name != "DataArray") continue;
        const std::string* t = c->attr("type");
        if (!t || !vtk_scalar(*t)) continue;  // strings and bit arrays are not fields
        const std::string* name = c->attr("Name");
        Array a = decode_array(*c, ctx, "PointData array", -1);
        if (a.count() != static_cast<std::uint64_t>(npts) * a.components)
          throw InputError(path + ": PointData array '" + (name ? *name : std::string()) + "' holds " +
                           std::to_string(a.count()) + " values for " + std::to_string(npts) + " points x " +
                           std::to_string(a.components) + " components");
        if (global_ids && ids_name && name && *name == *ids_name && a.components == 1) {
          // The piece's global point ids (exact integers, not a float field).
          for (std::size_t i = 0; i < a.count(); ++i) {
            std::int64_t v = 0;
            if (!a.as_int(i, v) || v < 0)
              throw InputError(path + ": GlobalIds array '" + *name + "' holds a non-integer or negative id at " +
                               std::to_string(i));
            global_ids->push_back(v);
          }
          piece_has_ids = true;
          continue;
        }
        Field f{name ? *name : std::string("array"), a.components, std::vector<float>(a.count())};
        for (std::size_t i = 0; i < a.count(); ++i) f.values[i] = static_cast<float>(a.as_double(i));
        fields.push_back(std::move(f));
      }
      // keymesh knows normals by the name "Normals": adopt the array the
      // file marks as normals under that name when nothing else has it.
      const std::string* marked = pd->attr("Normals");
      if (marked && *marked != "Normals") {
        bool taken = false;
        for (const Field& f : fields) taken = taken || f.name == "Normals";
        for (Field& f : fields)
          if (!taken && f.name == *marked && f.components == 3) f.name = "Normals";
      }
    }
    if (npts > 0) every_piece_has_ids = every_piece_has_ids && piece_has_ids;
    // Fields present in every piece survive; a piece without points adds nothing.
    if (first_piece) {
      mesh.point_fields = std::move(fields);
    } else if (npts > 0) {
      std::vector<Field> kept;
      for (Field& f : mesh.point_fields)
        for (Field& g : fields)
          if (g.name == f.name && g.components == f.components) {
            f.values.insert(f.values.end(), g.values.begin(), g.values.end());
            kept.push_back(std::move(f));
            break;
          }
      mesh.point_fields = std::move(kept);
    }
    first_piece = false;

    auto point_id = [&](const Array& conn, std::size_t i, const std::string& what) {
      std::int64_t v = 0;
      if (!conn.as_int(i, v) || v < 0 || v >= npts)
        throw InputError(path + ": " + what + " connectivity refers to point " + std::to_string(v) + " out of range (" +
                         std::to_string(npts) + " points)");
      return static_cast<PointIndex>(base + static_cast<std::uint64_t>(v));
    };
    if (auto polys = read_cells(piece, "Polys", npolys, ctx)) {
      std::uint64_t begin = 0;
      for (std::size_t c = 0; c < polys->ends.size(); ++c) {
        const std::uint64_t end = polys->ends[c];
        if (end - begin < 3)
          throw InputError(path + ": polygon " + std::to_string(c) + " has " + std::to_string(end - begin) +
                           " points (at least 3 needed)");
        for (std::uint64_t k = begin; k < end; ++k) mesh.connectivity.push_back(point_id(polys->connectivity, k, "Polys"));
        mesh.offsets.push_back(mesh.connectivity.size());
        begin = end;
      }
    }
    if (auto strips = read_cells(piece, "Strips", nstrips, ctx)) {
      std::uint64_t begin = 0;
      for (std::size_t c = 0; c < strips->ends.size(); ++c) {
        const std::uint64_t end = strips->ends[c];
        // Strip triangle j is (j, j+1, j+2), every other one flipped to keep orientation.
        for (std::uint64_t j = begin; j + 2 < end; ++j) {
          const bool odd = (j - begin) % 2 == 1;
          const PointIndex a = point_id(strips->connectivity, j, "Strips");
          const PointIndex b = point_id(strips->connectivity, j + 1, "Strips");
          const PointIndex d = point_id(strips->connectivity, j + 2, "Strips");
          mesh.connectivity.push_back(odd ? b : a);
          mesh.connectivity.push_back(odd ? a : b);
          mesh.connectivity.push_back(d);
          mesh.offsets.push_back(mesh.connectivity.size());
        }
        begin = end;
      }
    }
  }
  if (mesh.offsets.size() == 1) mesh.offsets.clear();
  compact_offsets(mesh);
  if (global_ids && !every_piece_has_ids) global_ids->clear();
  // What every caller relies on (non-finite coordinates included): the
  // parser's own result is checked, not only read_mesh's.
  validate_mesh(mesh, path);
  return mesh;
}

SurfaceMesh read_pvtp(const std::string& path) {
  const std::string index = read_whole_file(path);
  ParsedXml xml = parse_xml(index, path);
  const XmlNode* root = xml.root.get();
  const std::string* type = root ? root->attr("type") : nullptr;
  const XmlNode* ppoly = root ? root->child("PPolyData") : nullptr;
  if (!type || *type != "PPolyData" || !ppoly) throw InputError(path + ": not a VTK PPolyData index (.pvtp)");
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  // Every piece, with its global point ids when it has them.
  std::vector<SurfaceMesh> pieces;
  std::vector<std::vector<std::int64_t>> ids;
  for (const auto& c : ppoly->children) {
    if (c->name != "Piece") continue;
    const std::string* source = c->attr("Source");
    if (!source || source->empty()) throw InputError(path + ": <Piece> without a Source");
    std::filesystem::path p(*source);
    if (p.is_relative()) p = dir / p;
    const std::string data = read_whole_file(p.string());
    ids.emplace_back();
    pieces.push_back(parse_vtp(data, p.string(), &ids.back()));
  }
  if (pieces.empty()) throw InputError(path + ": the index lists no pieces");
  bool welded = true;
  std::int64_t max_id = -1;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    if (pieces[i].num_points() > 0 && ids[i].empty()) welded = false;
    for (std::int64_t v : ids[i]) max_id = std::max(max_id, v);
  }
  SurfaceMesh out;
  // Fields every piece with points has (name and components), in the first's order.
  std::vector<Field> fields;
  const SurfaceMesh* first = nullptr;
  for (const SurfaceMesh& m : pieces)
    if (m.num_points() > 0) {
      first = &m;
      break;
    }
  if (first)
    for (const Field& f : first->point_fields) {
      bool everywhere = true;
      for (const SurfaceMesh& m : pieces) {
        if (m.num_points() == 0) continue;
        bool has = false;
        for (const Field& g : m.point_fields) has = has || (g.name == f.name && g.components == f.components);
        everywhere = everywhere && has;
      }
      if (everywhere) fields.push_back(Field{f.name, f.components, {}});
    }
  auto field_of = [](const SurfaceMesh& m, const Field& like) -> const Field* {
    for (const Field& g : m.point_fields)
      if (g.name == like.name && g.components == like.components) return &g;
    return nullptr;
  };
  bool polygons = false;
  for (const SurfaceMesh& m : pieces) polygons = polygons || !m.all_triangles();
  if (polygons) out.offsets.push_back(0);
  auto add_cells = [&](const SurfaceMesh& m, auto&& id_of) {
    for (Id c = 0; c < m.num_cells(); ++c) {
      for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k) out.connectivity.push_back(id_of(m.connectivity[k]));
      if (polygons) out.offsets.push_back(out.connectivity.size());
    }
  };
  if (welded && max_id >= 0) {
    // Welded by the ids the pieces carry (no positions compared): point g of
    // the whole mesh is the piece point with global id g; every copy of a
    // shared point must agree on its position.
    if (static_cast<std::uint64_t>(max_id) >= std::numeric_limits<PointIndex>::max())
      throw LimitError(path + ": global point id " + std::to_string(max_id) + " exceeds 2^32 - 2");
    // Ids are dense (0 .. distinct points - 1): one past what the pieces
    // hold is refused before anything of that size is allocated.
    std::uint64_t held = 0;
    for (const SurfaceMesh& m : pieces) held += static_cast<std::uint64_t>(m.num_points());
    if (static_cast<std::uint64_t>(max_id) >= held)
      throw InputError(path + ": global point id " + std::to_string(max_id) + " but the pieces hold " +
                       std::to_string(held) + " points");
    const std::size_t n = static_cast<std::size_t>(max_id) + 1;
    std::vector<std::uint8_t> seen(n, 0);
    out.points.assign(3 * n, 0.0f);
    for (Field& f : fields) f.values.assign(n * static_cast<std::size_t>(f.components), 0.0f);
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      const SurfaceMesh& m = pieces[i];
      for (Id p = 0; p < m.num_points(); ++p) {
        const std::size_t g = static_cast<std::size_t>(ids[i][static_cast<std::size_t>(p)]);
        if (seen[g] && !std::equal(m.points.begin() + 3 * p, m.points.begin() + 3 * p + 3, out.points.begin() + 3 * g))
          throw InputError(path + ": pieces disagree on the position of global point " + std::to_string(g));
        seen[g] = 1;
        std::copy_n(m.points.begin() + 3 * p, 3, out.points.begin() + 3 * g);
        for (Field& f : fields) {
          const Field* src = field_of(m, f);
          std::copy_n(src->values.begin() + f.components * p, f.components, f.values.begin() + f.components * g);
        }
      }
      add_cells(m, [&](PointIndex local) { return static_cast<PointIndex>(ids[i][local]); });
    }
    for (std::size_t g = 0; g < n; ++g)
      if (!seen[g]) throw InputError(path + ": no piece holds global point " + std::to_string(g));
  } else {
    // No ids: the pieces side by side, as a multi-piece .vtp reads.
    for (const SurfaceMesh& m : pieces) {
      const std::uint64_t base = out.points.size() / 3;
      if (base + static_cast<std::uint64_t>(m.num_points()) > std::numeric_limits<PointIndex>::max())
        throw LimitError(path + ": more than 2^32 - 1 points");
      out.points.insert(out.points.end(), m.points.begin(), m.points.end());
      for (Field& f : fields)
        if (const Field* src = field_of(m, f)) f.values.insert(f.values.end(), src->values.begin(), src->values.end());
      add_cells(m, [&](PointIndex local) { return static_cast<PointIndex>(base + local); });
    }
  }
  out.point_fields = std::move(fields);
  return out;
}

namespace {

// The attributes of <PointData>/<PPointData>: the first 1-component field as
// Scalars, "Normals" as Normals, the global ids of a piece as GlobalIds.
std::string point_data_attributes(const SurfaceMesh& mesh, bool global_point_ids) {
  std::string a;
  for (const Field& f : mesh.point_fields)
    if (f.components == 1) {
      a += " Scalars=\"" + xml_escape(f.name) + "\"";
      break;
    }
  if (normals_field(mesh)) a += " Normals=\"Normals\"";
  if (global_point_ids) a += " GlobalIds=\"GlobalPointIds\"";
  return a;
}

}  // namespace

void write_vtp(const SurfaceMesh& mesh, const std::string& path) { write_vtp(mesh, path, nullptr); }

void write_vtp(const SurfaceMesh& mesh, const std::string& path, const std::vector<std::uint64_t>* global_point_ids) {
  validate_mesh(mesh, path);
  if (global_point_ids && global_point_ids->size() != static_cast<std::size_t>(mesh.num_points()))
    throw InputError(path + ": " + std::to_string(global_point_ids->size()) + " global point ids for " +
                     std::to_string(mesh.num_points()) + " points");
  const Id n = mesh.num_points();
  const Id cells = mesh.num_cells();

  // Appended blocks in file order: point fields, cell fields, points, connectivity, offsets.
  std::uint64_t offset = 0;
  auto block = [&](std::uint64_t bytes) {
    const std::uint64_t at = offset;
    offset += 8 + bytes;
    return std::to_string(at);
  };
  std::string x = "<?xml version=\"1.0\"?>\n";
  x += "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
  x += "  <PolyData>\n";
  x += "    <Piece NumberOfPoints=\"" + std::to_string(n) +
       "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"" + std::to_string(cells) + "\">\n";
  x += "      <PointData" + point_data_attributes(mesh, global_point_ids != nullptr) + ">\n";
  for (const Field& f : mesh.point_fields)
    x += "        <DataArray type=\"Float32\" Name=\"" + xml_escape(f.name) + "\" NumberOfComponents=\"" +
         std::to_string(f.components) + "\" format=\"appended\" offset=\"" + block(4 * f.values.size()) + "\"/>\n";
  if (global_point_ids)
    x += "        <DataArray type=\"Int64\" Name=\"GlobalPointIds\" format=\"appended\" offset=\"" +
         block(8 * global_point_ids->size()) + "\"/>\n";
  x += "      </PointData>\n";
  if (!mesh.cell_fields.empty()) {
    x += "      <CellData>\n";
    for (const Field& f : mesh.cell_fields)
      x += "        <DataArray type=\"Float32\" Name=\"" + xml_escape(f.name) + "\" NumberOfComponents=\"" +
           std::to_string(f.components) + "\" format=\"appended\" offset=\"" + block(4 * f.values.size()) + "\"/>\n";
    x += "      </CellData>\n";
  }
  x += "      <Points>\n";
  x += "        <DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" offset=\"" +
       block(4 * mesh.points.size()) + "\"/>\n";
  x += "      </Points>\n";
  x += "      <Polys>\n";
  x += "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"" +
       block(8 * mesh.connectivity.size()) + "\"/>\n";
  x += "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"" +
       block(8 * static_cast<std::uint64_t>(cells)) + "\"/>\n";
  x += "      </Polys>\n";
  x += "    </Piece>\n";
  x += "  </PolyData>\n";
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
  auto write_floats = [&](const std::vector<float>& v) {
    append_le(buf, static_cast<std::uint64_t>(4 * v.size()));
    if constexpr (std::endian::native == std::endian::little) {
      flush(true);
      file.write(v.data(), 4 * v.size());
    } else {
      for (float f : v) {
        append_le(buf, f);
        flush(false);
      }
    }
  };
  // An Int64 block: its byte count, then the values converted a chunk at a
  // time (little-endian), written with one call per chunk.
  auto write_int64s = [&](std::uint64_t count, auto&& value_at) {
    append_le(buf, static_cast<std::uint64_t>(8 * count));
    flush(true);
    std::vector<std::int64_t> chunk(static_cast<std::size_t>(std::min<std::uint64_t>(count, 1 << 16)));
    for (std::uint64_t at = 0; at < count; at += chunk.size()) {
      const std::size_t len = static_cast<std::size_t>(std::min<std::uint64_t>(chunk.size(), count - at));
      for (std::size_t i = 0; i < len; ++i) {
        std::int64_t v = static_cast<std::int64_t>(value_at(at + i));
        if constexpr (std::endian::native == std::endian::big) v = byteswap_value(v);
        chunk[i] = v;
      }
      file.write(chunk.data(), 8 * len);
    }
  };
  for (const Field& f : mesh.point_fields) write_floats(f.values);
  if (global_point_ids)
    write_int64s(global_point_ids->size(), [&](std::uint64_t i) { return (*global_point_ids)[i]; });
  for (const Field& f : mesh.cell_fields) write_floats(f.values);
  write_floats(mesh.points);
  write_int64s(mesh.connectivity.size(), [&](std::uint64_t i) { return mesh.connectivity[i]; });
  write_int64s(static_cast<std::uint64_t>(cells), [&](std::uint64_t c) { return mesh.cell_end(static_cast<Id>(c)); });
  buf += "\n  </AppendedData>\n</VTKFile>\n";
  flush(true);
  file.commit();
}

void write_pvtp(const std::string& path, const SurfaceMesh& like, const std::vector<std::string>& pieces,
                bool global_point_ids) {
  std::string x = "<?xml version=\"1.0\"?>\n";
  x += "<VTKFile type=\"PPolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
  x += "  <PPolyData GhostLevel=\"0\">\n";
  x += "    <PPointData" + point_data_attributes(like, global_point_ids) + ">\n";
  for (const Field& f : like.point_fields)
    x += "      <PDataArray type=\"Float32\" Name=\"" + xml_escape(f.name) + "\" NumberOfComponents=\"" +
         std::to_string(f.components) + "\"/>\n";
  if (global_point_ids) x += "      <PDataArray type=\"Int64\" Name=\"GlobalPointIds\"/>\n";
  x += "    </PPointData>\n";
  x += "    <PPoints>\n      <PDataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\"/>\n    </PPoints>\n";
  for (const std::string& p : pieces) x += "    <Piece Source=\"" + xml_escape(p) + "\"/>\n";
  x += "  </PPolyData>\n</VTKFile>\n";
  AtomicFile file(path);
  file.write(x);
  file.commit();
}

}  // namespace keymesh::io
