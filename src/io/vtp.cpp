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
#include "vtk_xml_writer.hpp"

namespace keymesh::io {

using namespace mesh_bytes;
using namespace vtk_xml;

namespace {

// VTK's ghost marks (vtkDataSetAttributes::GhostArrayName()): bits, of
// which DUPLICATEPOINT and DUPLICATECELL (both 1) say "another piece's".
constexpr const char* kGhostArray = "vtkGhostType";
constexpr std::uint8_t kDuplicate = 1;

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
  const FileBytes data = read_whole_file(path);
  return parse_vtp(data, path);
}

SurfaceMesh parse_vtp(std::string_view data, const std::string& path) {
  return parse_vtp(data, path, nullptr, nullptr);
}

namespace {

// A piece's points, appended to mesh.points: decoded first, so a
// NumberOfPoints the data does not back is refused before anything of that
// size is allocated.
void read_points(const XmlNode& piece, std::int64_t npts, const Context& ctx, SurfaceMesh& mesh) {
  if (npts > 0) {
    const XmlNode* pts = piece.child("Points");
    const XmlNode* arr = pts ? pts->child("DataArray") : nullptr;
    if (!arr) throw InputError(ctx.path + ": piece with " + std::to_string(npts) + " points has no <Points> array");
    const Array a = decode_array(*arr, ctx, "Points array", 3 * npts);
    mesh.points.reserve(mesh.points.size() + a.count());
    for (std::size_t i = 0; i < a.count(); ++i) mesh.points.push_back(static_cast<float>(a.as_double(i)));
  }
  if (mesh.points.size() / 3 > std::numeric_limits<PointIndex>::max())
    throw LimitError(ctx.path + ": more than 2^32 - 1 points");
}

// The piece's global point ids (exact integers, not a float field), appended.
void append_global_ids(const Array& a, const std::string& name, const std::string& path,
                       std::vector<std::int64_t>& out) {
  for (std::size_t i = 0; i < a.count(); ++i) {
    std::int64_t v = 0;
    if (!a.as_int(i, v) || v < 0)
      throw InputError(path + ": GlobalIds array '" + name + "' holds a non-integer or negative id at " +
                       std::to_string(i));
    out.push_back(v);
  }
}

// keymesh knows normals by the name "Normals": adopt the array the file
// marks as normals under that name when nothing else has it.
void adopt_marked_normals(const XmlNode& point_data, std::vector<Field>& fields) {
  const std::string* marked = point_data.attr("Normals");
  if (!marked || *marked == "Normals") return;
  bool taken = false;
  for (const Field& f : fields) taken = taken || f.name == "Normals";
  for (Field& f : fields)
    if (!taken && f.name == *marked && f.components == 3) f.name = "Normals";
}

// A piece's point or cell data (`section`, `what` its tag): every numeric
// array with one tuple per point (cell) becomes a float field; with
// `global_ids`, the array marked GlobalIds is appended there instead
// (has_ids says the piece had one).
struct PieceData {
  std::vector<Field> fields;
  bool has_ids = false;
  std::vector<std::uint8_t> ghosts;  // the vtkGhostType array (not a field), or empty
};
PieceData read_data(const XmlNode* section, std::int64_t tuples, const Context& ctx, const std::string& what,
                    std::vector<std::int64_t>* global_ids) {
  PieceData out;
  if (!section || tuples <= 0) return out;
  const std::string* ids_name = section->attr("GlobalIds");
  for (const auto& c : section->children) {
    if (c->name != "DataArray") continue;
    const std::string* t = c->attr("type");
    if (!t || !vtk_scalar(*t)) continue;  // strings and bit arrays are not fields
    const std::string* name = c->attr("Name");
    Array a = decode_array(*c, ctx, what + " array", -1);
    if (a.count() % static_cast<std::uint64_t>(a.components) != 0 ||
        a.count() / static_cast<std::uint64_t>(a.components) != static_cast<std::uint64_t>(tuples))
      throw InputError(ctx.path + ": " + what + " array '" + (name ? *name : std::string()) + "' holds " +
                       std::to_string(a.count()) + " values for " + std::to_string(tuples) +
                       (what == "PointData" ? " points x " : " cells x ") + std::to_string(a.components) +
                       " components");
    if (name && *name == kGhostArray && a.components == 1) {
      out.ghosts.resize(a.count());
      for (std::size_t i = 0; i < a.count(); ++i) {
        std::int64_t v = 0;
        if (!a.as_int(i, v) || v < 0 || v > 255)
          throw InputError(ctx.path + ": " + what + " array '" + *name + "' holds a value that is not a byte at " +
                           std::to_string(i));
        out.ghosts[i] = static_cast<std::uint8_t>(v);
      }
      continue;
    }
    if (global_ids && ids_name && name && *name == *ids_name && a.components == 1) {
      append_global_ids(a, *name, ctx.path, *global_ids);
      out.has_ids = true;
      continue;
    }
    Field f{name ? *name : std::string("array"), a.components, keymesh::Array<float>(a.count())};
    for (std::size_t i = 0; i < a.count(); ++i) f.values[i] = static_cast<float>(a.as_double(i));
    out.fields.push_back(std::move(f));
  }
  adopt_marked_normals(*section, out.fields);
  return out;
}

// The cell data of the polygons and strip triangles a piece appended:
// tuple source[c] of each field for appended cell c (VTK numbers a
// piece's cells verts, lines, polys, strips; a strip's tuple goes to each
// of its triangles).
std::vector<Field> cell_fields_of(std::vector<Field>&& all, const std::vector<std::uint64_t>& source) {
  bool identity = true;
  for (std::size_t c = 0; c < source.size() && identity; ++c) identity = source[c] == c;
  for (Field& f : all) {
    if (identity && f.values.size() == source.size() * static_cast<std::size_t>(f.components)) continue;
    const auto k = static_cast<std::size_t>(f.components);
    keymesh::Array<float> v(source.size() * k);
    for (std::size_t c = 0; c < source.size(); ++c) std::copy_n(f.values.begin() + source[c] * k, k, v.begin() + c * k);
    f.values = std::move(v);
  }
  return std::move(all);
}

// Fields present in every piece survive; a piece without tuples adds nothing.
void merge_piece_fields(std::vector<Field>& kept, std::vector<Field>& fields, bool first_piece, std::int64_t tuples) {
  if (first_piece) {
    kept = std::move(fields);
  } else if (tuples > 0) {
    std::vector<Field> out;
    for (Field& f : kept)
      for (Field& g : fields)
        if (g.name == f.name && g.components == f.components) {
          f.values.insert(f.values.end(), g.values.begin(), g.values.end());
          out.push_back(std::move(f));
          break;
        }
    kept = std::move(out);
  }
}

// Connectivity entries of one piece as ids of the whole mesh: in range of
// the piece's points, offset by the points of the pieces before it.
struct PieceIds {
  const std::string& path;
  std::uint64_t base;
  std::int64_t npts;
  PointIndex operator()(const Array& conn, std::size_t i, const char* what) const {
    std::int64_t v = 0;
    if (!conn.as_int(i, v) || v < 0 || v >= npts)
      throw InputError(path + ": " + what + " connectivity refers to point " + std::to_string(v) + " out of range (" +
                       std::to_string(npts) + " points)");
    return static_cast<PointIndex>(base + static_cast<std::uint64_t>(v));
  }
};

// Whether cell tuple c is a ghost cell (another piece's, carried for filters).
struct GhostCells {
  const std::vector<std::uint8_t>& marks;
  bool operator()(std::uint64_t c) const { return !marks.empty() && (marks[c] & kDuplicate); }
};

void append_polys(const CellArrays& polys, const PieceIds& id, std::uint64_t first_tuple, const GhostCells& ghost,
                  SurfaceMesh& mesh, std::vector<std::uint64_t>& source) {
  std::uint64_t begin = 0;
  for (std::size_t c = 0; c < polys.ends.size(); ++c) {
    const std::uint64_t end = polys.ends[c];
    if (end - begin < 3)
      throw InputError(id.path + ": polygon " + std::to_string(c) + " has " + std::to_string(end - begin) +
                       " points (at least 3 needed)");
    if (ghost(first_tuple + c)) {
      begin = end;
      continue;
    }
    for (std::uint64_t k = begin; k < end; ++k) mesh.connectivity.push_back(id(polys.connectivity, k, "Polys"));
    mesh.offsets.push_back(mesh.connectivity.size());
    source.push_back(first_tuple + c);
    begin = end;
  }
}

// Strip triangle j is (j, j+1, j+2), every other one flipped to keep orientation.
void append_strips(const CellArrays& strips, const PieceIds& id, std::uint64_t first_tuple, const GhostCells& ghost,
                   SurfaceMesh& mesh, std::vector<std::uint64_t>& source) {
  std::uint64_t begin = 0;
  for (std::size_t c = 0; c < strips.ends.size(); ++c) {
    const std::uint64_t end = strips.ends[c];
    for (std::uint64_t j = begin; j + 2 < end && !ghost(first_tuple + c); ++j) {
      const bool odd = (j - begin) % 2 == 1;
      const PointIndex a = id(strips.connectivity, j, "Strips");
      const PointIndex b = id(strips.connectivity, j + 1, "Strips");
      const PointIndex d = id(strips.connectivity, j + 2, "Strips");
      mesh.connectivity.push_back(odd ? b : a);
      mesh.connectivity.push_back(odd ? a : b);
      mesh.connectivity.push_back(d);
      mesh.offsets.push_back(mesh.connectivity.size());
      source.push_back(first_tuple + c);
    }
    begin = end;
  }
}

}  // namespace

SurfaceMesh parse_vtp(std::string_view data, const std::string& path, std::vector<std::int64_t>* global_ids,
                      std::vector<std::uint8_t>* duplicate_points) {
  if (global_ids) global_ids->clear();
  if (duplicate_points) duplicate_points->clear();
  bool every_piece_has_ids = true;
  ParsedXml xml = parse_xml(data, path);
  const Context ctx = file_context(xml, path, "PolyData");
  const XmlNode* poly = xml.root->child("PolyData");
  if (!poly) throw InputError(path + ": VTK file has no <PolyData>");

  SurfaceMesh mesh;
  mesh.offsets.push_back(0);
  bool first_piece = true, cells_started = false;
  for (const auto& piece_ptr : poly->children) {
    if (piece_ptr->name != "Piece") continue;
    const XmlNode& piece = *piece_ptr;
    const std::int64_t npts = count_attr(piece, "NumberOfPoints", path);
    const std::int64_t nverts = count_attr(piece, "NumberOfVerts", path);
    const std::int64_t nlines = count_attr(piece, "NumberOfLines", path);
    const std::int64_t npolys = count_attr(piece, "NumberOfPolys", path);
    const std::int64_t nstrips = count_attr(piece, "NumberOfStrips", path);
    const PieceIds id{path, mesh.points.size() / 3, npts};
    read_points(piece, npts, ctx, mesh);
    PieceData point_data = read_data(piece.child("PointData"), npts, ctx, "PointData", global_ids);
    if (npts > 0) every_piece_has_ids = every_piece_has_ids && point_data.has_ids;
    if (duplicate_points) {
      if (point_data.ghosts.empty())
        duplicate_points->resize(duplicate_points->size() + static_cast<std::size_t>(npts), 0);
      for (std::uint8_t g : point_data.ghosts) duplicate_points->push_back(g & kDuplicate);
    }
    merge_piece_fields(mesh.point_fields, point_data.fields, first_piece, npts);
    first_piece = false;
    // Cell data: one tuple per cell of every kind (verts and lines too,
    // whose cells keymesh does not keep), checked before the cells.
    const std::uint64_t first_poly = static_cast<std::uint64_t>(nverts) + static_cast<std::uint64_t>(nlines);
    const std::uint64_t all_cells = first_poly + static_cast<std::uint64_t>(npolys) + static_cast<std::uint64_t>(nstrips);
    PieceData cell_data = read_data(piece.child("CellData"), static_cast<std::int64_t>(all_cells), ctx, "CellData", nullptr);
    // Ghost cells (another piece's, carried for VTK's filters) are not this piece's mesh.
    const GhostCells ghost{cell_data.ghosts};
    std::vector<std::uint64_t> source;
    if (auto polys = read_cells(piece, "Polys", npolys, ctx)) append_polys(*polys, id, first_poly, ghost, mesh, source);
    if (auto strips = read_cells(piece, "Strips", nstrips, ctx))
      append_strips(*strips, id, first_poly + static_cast<std::uint64_t>(npolys), ghost, mesh, source);
    if (!source.empty()) {
      std::vector<Field> cells = cell_fields_of(std::move(cell_data.fields), source);
      merge_piece_fields(mesh.cell_fields, cells, !cells_started, static_cast<std::int64_t>(source.size()));
      cells_started = true;
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

namespace {

// The pieces a .pvtp index lists (Source paths relative to the index), each
// with its global point ids when it has them.
struct Pieces {
  std::vector<SurfaceMesh> meshes;
  std::vector<std::vector<std::int64_t>> ids;
  std::vector<std::vector<std::uint8_t>> duplicates;  // per point: 1 when another piece owns it
};
Pieces read_pieces(const std::string& path) {
  const FileBytes index = read_whole_file(path);
  ParsedXml xml = parse_xml(index, path);
  const XmlNode* root = xml.root.get();
  const std::string* type = root ? root->attr("type") : nullptr;
  const XmlNode* ppoly = root ? root->child("PPolyData") : nullptr;
  if (!type || *type != "PPolyData" || !ppoly) throw InputError(path + ": not a VTK PPolyData index (.pvtp)");
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  Pieces pieces;
  for (const auto& c : ppoly->children) {
    if (c->name != "Piece") continue;
    const std::string* source = c->attr("Source");
    if (!source || source->empty()) throw InputError(path + ": <Piece> without a Source");
    std::filesystem::path p(*source);
    if (p.is_relative()) p = dir / p;
    const FileBytes data = read_whole_file(p.string());
    pieces.ids.emplace_back();
    pieces.duplicates.emplace_back();
    pieces.meshes.push_back(parse_vtp(data, p.string(), &pieces.ids.back(), &pieces.duplicates.back()));
  }
  if (pieces.meshes.empty()) throw InputError(path + ": the index lists no pieces");
  return pieces;
}

const Field* field_of(const std::vector<Field>& fields, const Field& like) {
  for (const Field& g : fields)
    if (g.name == like.name && g.components == like.components) return &g;
  return nullptr;
}
const Field* field_of(const SurfaceMesh& m, const Field& like) { return field_of(m.point_fields, like); }

// Fields every piece with tuples has (name and components), in the first's
// order, without values: `of` picks the point or the cell fields, `count`
// the piece's points or cells.
std::vector<Field> common_fields(const std::vector<SurfaceMesh>& pieces, std::vector<Field> SurfaceMesh::*of,
                                 Id (SurfaceMesh::*count)() const) {
  std::vector<Field> fields;
  const auto has_tuples = [&](const SurfaceMesh& m) { return (m.*count)() > 0; };
  const auto first = std::find_if(pieces.begin(), pieces.end(), has_tuples);
  if (first == pieces.end()) return fields;
  for (const Field& f : (*first).*of) {
    bool everywhere = true;
    for (const SurfaceMesh& m : pieces)
      if (has_tuples(m)) everywhere = everywhere && field_of(m.*of, f);
    if (everywhere) fields.push_back(Field{f.name, f.components, {}});
  }
  return fields;
}

// A piece's cells appended to out, point ids mapped by id_of; offsets kept
// when any piece has a polygon.
template <class IdOf>
void append_cells(SurfaceMesh& out, const SurfaceMesh& m, bool polygons, IdOf id_of) {
  for (Id c = 0; c < m.num_cells(); ++c) {
    for (std::uint64_t k = m.cell_begin(c); k < m.cell_end(c); ++k)
      out.connectivity.push_back(id_of(m.connectivity[k]));
    if (polygons) out.offsets.push_back(out.connectivity.size());
  }
}

// Welded by the ids the pieces carry (no positions compared): point g of the
// whole mesh is the piece point with global id g; every copy of a shared
// point must agree on its position, and its fields are its owner's (the
// copy not marked DUPLICATEPOINT; the last copy when none is marked).
void weld_by_global_ids(const std::string& path, const Pieces& pieces, std::int64_t max_id, bool polygons,
                        std::vector<Field>& fields, SurfaceMesh& out) {
  if (static_cast<std::uint64_t>(max_id) >= std::numeric_limits<PointIndex>::max())
    throw LimitError(path + ": global point id " + std::to_string(max_id) + " exceeds 2^32 - 2");
  // Ids are dense (0 .. distinct points - 1): one past what the pieces
  // hold is refused before anything of that size is allocated.
  std::uint64_t held = 0;
  for (const SurfaceMesh& m : pieces.meshes) held += static_cast<std::uint64_t>(m.num_points());
  if (static_cast<std::uint64_t>(max_id) >= held)
    throw InputError(path + ": global point id " + std::to_string(max_id) + " but the pieces hold " +
                     std::to_string(held) + " points");
  const std::size_t n = static_cast<std::size_t>(max_id) + 1;
  std::vector<std::uint8_t> seen(n, 0);
  out.points.assign(3 * n, 0.0f);
  for (Field& f : fields) f.values.assign(n * static_cast<std::size_t>(f.components), 0.0f);
  for (std::size_t i = 0; i < pieces.meshes.size(); ++i) {
    const SurfaceMesh& m = pieces.meshes[i];
    const std::vector<std::int64_t>& ids = pieces.ids[i];
    const std::vector<std::uint8_t>& duplicate = pieces.duplicates[i];
    for (Id p = 0; p < m.num_points(); ++p) {
      const std::size_t g = static_cast<std::size_t>(ids[static_cast<std::size_t>(p)]);
      if (seen[g] && !std::equal(m.points.begin() + 3 * p, m.points.begin() + 3 * p + 3, out.points.begin() + 3 * g))
        throw InputError(path + ": pieces disagree on the position of global point " + std::to_string(g));
      // seen: 1 a duplicate's copy so far, 2 the owner's.
      if (seen[g] == 2) continue;
      seen[g] = duplicate[static_cast<std::size_t>(p)] ? 1 : 2;
      std::copy_n(m.points.begin() + 3 * p, 3, out.points.begin() + 3 * g);
      for (Field& f : fields) {
        const Field* src = field_of(m, f);
        std::copy_n(src->values.begin() + f.components * p, f.components, f.values.begin() + f.components * g);
      }
    }
    append_cells(out, m, polygons, [&](PointIndex local) { return static_cast<PointIndex>(ids[local]); });
  }
  for (std::size_t g = 0; g < n; ++g)
    if (!seen[g]) throw InputError(path + ": no piece holds global point " + std::to_string(g));
}

// No ids: the pieces side by side, as a multi-piece .vtp reads.
void concatenate(const std::string& path, const Pieces& pieces, bool polygons, std::vector<Field>& fields,
                 SurfaceMesh& out) {
  for (const SurfaceMesh& m : pieces.meshes) {
    const std::uint64_t base = out.points.size() / 3;
    if (base + static_cast<std::uint64_t>(m.num_points()) > std::numeric_limits<PointIndex>::max())
      throw LimitError(path + ": more than 2^32 - 1 points");
    out.points.insert(out.points.end(), m.points.begin(), m.points.end());
    for (Field& f : fields)
      if (const Field* src = field_of(m, f)) f.values.insert(f.values.end(), src->values.begin(), src->values.end());
    append_cells(out, m, polygons, [&](PointIndex local) { return static_cast<PointIndex>(base + local); });
  }
}

}  // namespace

SurfaceMesh read_pvtp(const std::string& path) {
  const Pieces pieces = read_pieces(path);
  bool welded = true;
  std::int64_t max_id = -1;
  for (std::size_t i = 0; i < pieces.meshes.size(); ++i) {
    if (pieces.meshes[i].num_points() > 0 && pieces.ids[i].empty()) welded = false;
    for (std::int64_t v : pieces.ids[i]) max_id = std::max(max_id, v);
  }
  std::vector<Field> fields = common_fields(pieces.meshes, &SurfaceMesh::point_fields, &SurfaceMesh::num_points);
  bool polygons = false;
  for (const SurfaceMesh& m : pieces.meshes) polygons = polygons || !m.all_triangles();
  SurfaceMesh out;
  if (polygons) out.offsets.push_back(0);
  if (welded && max_id >= 0) weld_by_global_ids(path, pieces, max_id, polygons, fields, out);
  else concatenate(path, pieces, polygons, fields, out);
  out.point_fields = std::move(fields);
  // Cells are appended piece after piece, either way: so are their fields.
  out.cell_fields = common_fields(pieces.meshes, &SurfaceMesh::cell_fields, &SurfaceMesh::num_cells);
  for (Field& f : out.cell_fields)
    for (const SurfaceMesh& m : pieces.meshes)
      if (const Field* src = field_of(m.cell_fields, f); src && m.num_cells() > 0)
        f.values.insert(f.values.end(), src->values.begin(), src->values.end());
  return out;
}

namespace {

// The attributes of <PointData>/<PPointData>: the fields' Scalars and
// Normals, the global ids of a piece as GlobalIds.
std::string point_data_attributes(const SurfaceMesh& mesh, bool global_point_ids) {
  return vtk_xml::field_attributes(mesh.point_fields) + (global_point_ids ? " GlobalIds=\"GlobalPointIds\"" : "");
}

// A field's <PDataArray> line in a .pvtp index.
std::string declared_array(const Field& f) {
  return "      <PDataArray type=\"Float32\" Name=\"" + xml_escape(f.name) + "\" NumberOfComponents=\"" +
         std::to_string(f.components) + "\"/>\n";
}

}  // namespace

void write_vtp(const SurfaceMesh& mesh, const std::string& path) { write_vtp(mesh, path, nullptr); }

void write_vtp(const SurfaceMesh& mesh, const std::string& path, const std::vector<std::uint64_t>* global_point_ids,
               const PieceGhosts* ghosts, const std::vector<UInt64PointArray>& uint64_arrays) {
  validate_mesh(mesh, path);
  for (const UInt64PointArray& a : uint64_arrays)
    if (!a.values || a.values->size() != static_cast<std::size_t>(mesh.num_points()))
      throw InputError(path + ": point array '" + a.name + "' holds " + std::to_string(a.values ? a.values->size() : 0) +
                       " values for " + std::to_string(mesh.num_points()) + " points");
  if (global_point_ids && global_point_ids->size() != static_cast<std::size_t>(mesh.num_points()))
    throw InputError(path + ": " + std::to_string(global_point_ids->size()) + " global point ids for " +
                     std::to_string(mesh.num_points()) + " points");
  const Id cells = mesh.num_cells();
  if (ghosts && (ghosts->points.size() != static_cast<std::size_t>(mesh.num_points()) ||
                 ghosts->cells.size() != static_cast<std::size_t>(cells)))
    throw InputError(path + ": ghost marks for " + std::to_string(ghosts->points.size()) + " points and " +
                     std::to_string(ghosts->cells.size()) + " cells");
  // Appended blocks in file order: point fields (and global ids, ghost
  // marks), cell fields (and ghost marks), points, connectivity, offsets.
  vtk_xml::AppendedArrays arrays;
  const auto ghost_array = [&](const std::vector<std::uint8_t>& marks) {
    return arrays.bytes(ScalarType::UInt8, kGhostArray, 1, marks.data(), marks.size());
  };
  std::string x = vtk_xml::file_header("PolyData") + "  <PolyData>\n";
  x += "    <Piece NumberOfPoints=\"" + std::to_string(mesh.num_points()) +
       "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"" + std::to_string(cells) +
       "\">\n";
  x += "      <PointData" + point_data_attributes(mesh, global_point_ids != nullptr) + ">\n";
  for (const Field& f : mesh.point_fields) x += arrays.floats(f.name, f.components, f.values);
  for (const UInt64PointArray& a : uint64_arrays)
    x += arrays.bytes(ScalarType::UInt64, a.name, 1, a.values->data(), a.values->size() * sizeof(std::uint64_t));
  if (global_point_ids)
    x += arrays.integers(ScalarType::Int64, "GlobalPointIds", global_point_ids->size(),
                         [&](std::uint64_t i) { return (*global_point_ids)[i]; });
  if (ghosts) x += ghost_array(ghosts->points);
  x += "      </PointData>\n";
  if (!mesh.cell_fields.empty() || ghosts) {
    x += "      <CellData>\n";
    for (const Field& f : mesh.cell_fields) x += arrays.floats(f.name, f.components, f.values);
    if (ghosts) x += ghost_array(ghosts->cells);
    x += "      </CellData>\n";
  }
  x += "      <Points>\n" + arrays.floats("Points", 3, mesh.points) + "      </Points>\n";
  x += "      <Polys>\n";
  x += arrays.integers(ScalarType::Int64, "connectivity", mesh.connectivity.size(),
                       [&](std::uint64_t i) { return mesh.connectivity[i]; });
  x += arrays.integers(ScalarType::Int64, "offsets", static_cast<std::uint64_t>(cells),
                       [&](std::uint64_t c) { return mesh.cell_end(static_cast<Id>(c)); });
  x += "      </Polys>\n    </Piece>\n  </PolyData>\n";
  arrays.write(path, x);
}

void write_pvtp(const std::string& path, const SurfaceMesh& like, const std::vector<std::string>& pieces,
                bool global_point_ids) {
  write_pvtp(path, like, pieces, global_point_ids, false);
}

void write_pvtp(const std::string& path, const SurfaceMesh& like, const std::vector<std::string>& pieces,
                bool global_point_ids, bool ghosts, const std::vector<std::string>& uint64_arrays) {
  const std::string ghost_array = std::string("      <PDataArray type=\"UInt8\" Name=\"") + kGhostArray + "\"/>\n";
  std::string x = vtk_xml::file_header("PPolyData");
  x += std::string("  <PPolyData GhostLevel=\"") + (ghosts ? "1" : "0") + "\">\n";
  x += "    <PPointData" + point_data_attributes(like, global_point_ids) + ">\n";
  for (const Field& f : like.point_fields) x += declared_array(f);
  for (const std::string& name : uint64_arrays)
    x += "      <PDataArray type=\"UInt64\" Name=\"" + xml_escape(name) + "\"/>\n";
  if (global_point_ids) x += "      <PDataArray type=\"Int64\" Name=\"GlobalPointIds\"/>\n";
  if (ghosts) x += ghost_array;
  x += "    </PPointData>\n";
  if (!like.cell_fields.empty() || ghosts) {
    x += "    <PCellData>\n";
    for (const Field& f : like.cell_fields) x += declared_array(f);
    if (ghosts) x += ghost_array;
    x += "    </PCellData>\n";
  }
  x += "    <PPoints>\n      <PDataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\"/>\n    </PPoints>\n";
  for (const std::string& p : pieces) x += "    <Piece Source=\"" + xml_escape(p) + "\"/>\n";
  x += "  </PPolyData>\n</VTKFile>\n";
  AtomicFile file(path);
  file.write(x);
  file.commit();
}

}  // namespace keymesh::io
