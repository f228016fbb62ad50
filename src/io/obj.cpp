#include "mesh_formats.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "mesh_bytes.hpp"

#include "checked_mesh.hpp"

namespace keymesh::io {

using namespace mesh_bytes;

SurfaceMesh read_obj(const std::string& path) { return parse_obj(read_whole_file(path), path); }

namespace {

// Resolves a 1-based or negative (relative to the current count) OBJ index
// to 0-based; returns false when it is 0 or out of range.
bool resolve_index(std::string_view token, std::int64_t count, std::int64_t& out) {
  std::int64_t v = 0;
  if (!parse_int64(token, v) || v == 0) return false;
  out = v > 0 ? v - 1 : count + v;
  return out >= 0 && out < count;
}

// Errors of a line: "<path>: line <n>: <what>".
struct LineError {
  const std::string& path;
  std::size_t line = 0;
  InputError operator()(const std::string& what) const {
    return InputError(path + ": line " + std::to_string(line) + ": " + what);
  }
};

// The vn normals read so far and which one each face corner names.
struct CornerNormals {
  std::vector<float> normals;          // vn lines, 3 per normal
  std::vector<std::int64_t> of_corner;  // per connectivity entry, -1 when absent
  bool usable = true;                   // false once a corner names none
};

// x y z of a "v" or "vn" line.
std::array<double, 3> read_xyz(TokenCursor& tok, const LineError& fail, const char* what) {
  std::array<double, 3> xyz;
  for (double& c : xyz)
    if (!parse_double(tok.next(), c)) throw fail(what);
  return xyz;
}

// The corners of an "f" line (a, a/t, a//n, a/t/n), appended as one cell.
void read_face(TokenCursor& tok, SurfaceMesh& mesh, CornerNormals& cn, const LineError& fail) {
  const auto nv = static_cast<std::int64_t>(mesh.points.size() / 3);
  const auto nn = static_cast<std::int64_t>(cn.normals.size() / 3);
  std::size_t corners = 0;
  for (std::string_view t = tok.next(); !t.empty(); t = tok.next(), ++corners) {
    const std::size_t s1 = t.find('/');
    const std::string_view vpart = t.substr(0, s1);
    std::int64_t v = 0;
    if (!resolve_index(vpart, nv, v))
      throw fail("face vertex index '" + std::string(vpart.substr(0, 30)) + "' out of range (" +
                 std::to_string(nv) + " vertices so far)");
    mesh.connectivity.push_back(static_cast<PointIndex>(v));
    std::int64_t n = -1;
    if (s1 != std::string_view::npos) {
      const std::size_t s2 = t.find('/', s1 + 1);
      if (s2 != std::string_view::npos && s2 + 1 < t.size()) {
        if (!resolve_index(t.substr(s2 + 1), nn, n)) throw fail("face normal index out of range");
      }
    }
    if (n < 0) cn.usable = false;
    if (cn.usable) cn.of_corner.push_back(n);
  }
  if (corners < 3) throw fail("face with " + std::to_string(corners) + " vertices (at least 3 needed)");
  mesh.offsets.push_back(mesh.connectivity.size());
}

// Normals become a point field only when each point gets exactly one normal.
void add_point_normals(SurfaceMesh& mesh, const CornerNormals& cn) {
  if (!cn.usable || cn.normals.empty() || mesh.connectivity.empty()) return;
  const std::size_t np = mesh.points.size() / 3;
  std::vector<std::int64_t> of_point(np, -1);
  for (std::size_t i = 0; i < mesh.connectivity.size(); ++i) {
    std::int64_t& slot = of_point[mesh.connectivity[i]];
    if (slot < 0) slot = cn.of_corner[i];
    else if (slot != cn.of_corner[i]) return;
  }
  for (std::size_t p = 0; p < np; ++p)
    if (of_point[p] < 0) return;  // unused point: no normal to give it
  Field f{"Normals", 3, Array<float>(3 * np)};
  for (std::size_t p = 0; p < np; ++p)
    for (int a = 0; a < 3; ++a) f.values[3 * p + a] = cn.normals[3 * of_point[p] + a];
  mesh.point_fields.push_back(std::move(f));
}

}  // namespace

SurfaceMesh parse_obj(std::string_view data, const std::string& path) {
  SurfaceMesh mesh;
  CornerNormals cn;
  mesh.offsets.push_back(0);
  LineError fail{path};
  std::size_t pos = 0;
  while (pos < data.size()) {
    ++fail.line;
    std::size_t end = data.find('\n', pos);
    if (end == std::string_view::npos) end = data.size();
    std::string_view line = data.substr(pos, end - pos);
    pos = end + 1;
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    TokenCursor tok(line);
    const std::string_view key = tok.next();
    if (key == "v") {
      const auto xyz = read_xyz(tok, fail, "bad vertex coordinate");
      if (mesh.points.size() / 3 >= std::numeric_limits<PointIndex>::max())
        throw LimitError(path + ": more than 2^32 - 1 vertices");
      for (double c : xyz) mesh.points.push_back(static_cast<float>(c));
    } else if (key == "vn") {
      for (double c : read_xyz(tok, fail, "bad normal")) cn.normals.push_back(static_cast<float>(c));
    } else if (key == "f") {
      read_face(tok, mesh, cn, fail);
    }
    // Everything else (vt, g, o, s, usemtl, mtllib, l, p, ...) carries no surface geometry.
  }
  if (mesh.offsets.size() == 1) mesh.offsets.clear();
  compact_offsets(mesh);
  add_point_normals(mesh, cn);
  return checked_mesh(std::move(mesh), path);
}

namespace {

// `count` lines of one section, formatted on the threads a round at a time
// (16 parts a round, each into its own text, taken by whichever thread is
// free), written in order: the same text at any thread count. Formatting
// floats is most of an .obj's cost. A round of a few lines is one part,
// formatted where it is: waking the threads would cost more. (The parts
// once ran as a parallel region of 16 threads, 16 on a 2-core machine.)
template <class Line>
void write_lines(AtomicFile& file, Id count, const Line& line) {
  constexpr Id kRound = Id{1} << 16, kFewLines = 4096;
  constexpr int kParts = 16;
  std::vector<std::string> text(kParts);
  for (Id first = 0; first < count; first += kRound) {
    const Id n = std::min(kRound, count - first);
    const int parts = n < kFewLines ? 1 : kParts;
    parallel::for_each_dynamic(
        parts,
        [&](Id part) {
          std::string& t = text[static_cast<std::size_t>(part)];
          const auto p = static_cast<int>(part);
          for (Id i = parallel::chunk_begin(n, parts, p); i < parallel::chunk_begin(n, parts, p + 1); ++i)
            line(t, first + i);
        },
        1);
    for (std::string& t : text) {  // cleared here: a part may get no lines in the next round
      if (!t.empty()) file.write(t);
      t.clear();
    }
  }
}

}  // namespace

void write_obj(const SurfaceMesh& mesh, const std::string& path) {
  validate_mesh(mesh, path);
  const Field* normals = normals_field(mesh);
  const Id n = mesh.num_points();
  const Id cells = mesh.num_cells();
  AtomicFile file(path);
  file.write("# written by keymesh\n");
  auto vector_line = [](std::string_view tag, const float* v) {
    return [tag, v](std::string& t, Id i) {
      t += tag;
      for (int a = 0; a < 3; ++a) {
        t += ' ';
        append_float_text(t, v[3 * i + a]);
      }
      t += '\n';
    };
  };
  write_lines(file, n, vector_line("v", mesh.points.data()));
  if (normals) write_lines(file, n, vector_line("vn", normals->values.data()));
  write_lines(file, cells, [&](std::string& t, Id c) {
    t += 'f';
    for (std::uint64_t k = mesh.cell_begin(c); k < mesh.cell_end(c); ++k) {
      t += ' ';
      const std::uint64_t id = std::uint64_t(mesh.connectivity[k]) + 1;
      append_uint_text(t, id);
      if (normals) {
        t += "//";
        append_uint_text(t, id);
      }
    }
    t += '\n';
  });
  file.commit();
}

}  // namespace keymesh::io
