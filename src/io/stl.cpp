#include "mesh_formats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/io/atomic_file.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "mesh_bytes.hpp"
#include "keymesh/weld/vertex_weld.hpp"

#include "checked_mesh.hpp"

namespace keymesh::io {

using namespace mesh_bytes;

SurfaceMesh read_stl(const std::string& path) { return parse_stl(read_whole_file(path), path); }

namespace {

// Turns a triangle soup (9 floats per triangle) into a mesh by welding equal
// positions; points are numbered in order of first appearance so the result
// does not depend on the weld's internal (sorted) numbering.
SurfaceMesh weld_soup(const std::vector<float>& soup, const std::string& path) {
  const Id corners = static_cast<Id>(soup.size() / 3);
  if (corners > Id{std::numeric_limits<PointIndex>::max()})
    throw LimitError(path + ": " + std::to_string(corners / 3) + " triangles exceed the 2^32 - 1 corner limit");
  SurfaceMesh mesh;
  if (corners == 0) return mesh;
  const weld::WeldResult w = weld::vertex_weld(soup.data(), corners);
  std::vector<PointIndex> renumber(w.first.size(), std::numeric_limits<PointIndex>::max());
  mesh.connectivity.resize(static_cast<std::size_t>(corners));
  PointIndex next = 0;
  for (Id i = 0; i < corners; ++i) {
    PointIndex& r = renumber[w.index_map[i]];
    if (r == std::numeric_limits<PointIndex>::max()) {
      r = next++;
      mesh.points.insert(mesh.points.end(), soup.begin() + 3 * i, soup.begin() + 3 * i + 3);
    }
    mesh.connectivity[i] = r;
  }
  return mesh;
}

SurfaceMesh parse_binary(std::string_view data, std::uint32_t count, const std::string& path) {
  std::vector<float> soup(std::size_t{count} * 9);
  const char* p = data.data() + 84;
  for (std::uint32_t t = 0; t < count; ++t, p += 50)
    for (int k = 0; k < 9; ++k) soup[std::size_t{t} * 9 + k] = load<float>(p + 12 + 4 * k, false);
  return weld_soup(soup, path);
}

SurfaceMesh parse_ascii(std::string_view data, const std::string& path) {
  TokenCursor tok(data);
  std::vector<float> soup;
  auto fail = [&](const std::string& what) -> InputError {
    return InputError(path + ": line " + std::to_string(tok.line()) + ": " + what);
  };
  auto expect = [&](std::string_view word) {
    const std::string_view t = tok.next();
    if (t != word) throw fail("expected '" + std::string(word) + "', found '" + std::string(t.substr(0, 40)) + "'");
  };
  bool any_solid = false;
  while (!tok.at_end()) {
    const std::string_view t = tok.next();
    if (t != "solid") throw fail("expected 'solid', found '" + std::string(t.substr(0, 40)) + "'");
    any_solid = true;
    tok.skip_line();  // the solid's name
    for (;;) {
      const std::string_view w = tok.next();
      if (w.empty()) throw fail("truncated file: missing 'endsolid'");
      if (w == "endsolid") {
        tok.skip_line();
        break;
      }
      if (w != "facet") throw fail("expected 'facet' or 'endsolid', found '" + std::string(w.substr(0, 40)) + "'");
      expect("normal");
      double ignored = 0;
      for (int k = 0; k < 3; ++k)
        if (!parse_double(tok.next(), ignored)) throw fail("bad facet normal");
      expect("outer");
      expect("loop");
      for (int v = 0; v < 3; ++v) {
        expect("vertex");
        for (int k = 0; k < 3; ++k) {
          double c = 0;
          if (!parse_double(tok.next(), c)) throw fail("bad vertex coordinate");
          soup.push_back(static_cast<float>(c));
        }
      }
      expect("endloop");
      expect("endfacet");
    }
  }
  if (!any_solid) throw fail("empty STL file");
  return weld_soup(soup, path);
}

bool starts_with_solid(std::string_view data) {
  std::size_t i = 0;
  while (i < data.size() && is_space(data[i])) ++i;
  return data.substr(i, 5) == "solid" && (i + 5 >= data.size() || is_space(data[i + 5]));
}

}  // namespace

SurfaceMesh parse_stl(std::string_view data, const std::string& path) {
  // Many binary writers start the 80-byte header with "solid" too, so the
  // exact binary size decides first.
  if (data.size() >= 84) {
    const std::uint32_t count = load<std::uint32_t>(data.data() + 80, false);
    const std::uint64_t expected = 84 + 50 * std::uint64_t{count};
    if (expected == data.size()) return checked_mesh(parse_binary(data, count, path), path);
    if (!starts_with_solid(data))
      throw InputError(path + ": binary STL declares " + std::to_string(count) + " triangles (" +
                       std::to_string(expected) + " bytes) but the file has " + std::to_string(data.size()) +
                       " bytes");
  }
  if (!starts_with_solid(data)) throw InputError(path + ": not an STL file (too short for binary, no 'solid')");
  return checked_mesh(parse_ascii(data, path), path);
}

void write_stl(const SurfaceMesh& mesh, const std::string& path) {
  validate_mesh(mesh, path);
  const Id cells = mesh.num_cells();
  std::uint64_t triangles = 0;
  for (Id c = 0; c < cells; ++c) {
    const std::uint64_t size = mesh.cell_end(c) - mesh.cell_begin(c);
    if (size >= 3) triangles += size - 2;  // cells of 1 or 2 points have no area
  }
  if (triangles > std::numeric_limits<std::uint32_t>::max())
    throw LimitError(path + ": " + std::to_string(triangles) + " triangles exceed binary STL's 2^32 - 1");

  AtomicFile file(path);
  std::string header(80, ' ');
  const std::string_view title = "binary STL written by keymesh";
  header.replace(0, title.size(), title);
  append_le(header, static_cast<std::uint32_t>(triangles));
  file.write(header);
  // 50-byte records (normal, three corners, attribute 0) filled a block at
  // a time, on the threads for a triangle mesh (each record is its own
  // triangle's: the bytes do not depend on the threads), then written.
  constexpr std::size_t kRecord = 50, kPerBlock = std::size_t{1} << 16;
  std::unique_ptr<char[]> block(new char[kRecord * kPerBlock]);
  const float* pts = mesh.points.data();
  auto record = [&](char* out, PointIndex a, PointIndex b, PointIndex c) {
    const float* p[3] = {pts + 3 * std::size_t{a}, pts + 3 * std::size_t{b}, pts + 3 * std::size_t{c}};
    double u[3], v[3];
    for (int k = 0; k < 3; ++k) {
      u[k] = double(p[1][k]) - p[0][k];
      v[k] = double(p[2][k]) - p[0][k];
    }
    double nrm[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double len = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    float values[12];
    for (int k = 0; k < 3; ++k) values[k] = static_cast<float>(len > 0 ? nrm[k] / len : 0.0);
    for (int q = 0; q < 3; ++q)
      for (int k = 0; k < 3; ++k) values[3 + 3 * q + k] = p[q][k];
    for (int k = 0; k < 12; ++k) store_le(out + 4 * k, values[k]);
    out[48] = out[49] = 0;
  };
  const PointIndex* conn = mesh.connectivity.data();
  if (mesh.offsets.empty()) {
    for (Id first = 0; first < cells; first += static_cast<Id>(kPerBlock)) {
      const Id count = std::min<Id>(cells - first, static_cast<Id>(kPerBlock));
      parallel::for_each(count, [&](Id t) {
        const PointIndex* c = conn + 3 * (first + t);
        record(block.get() + kRecord * static_cast<std::size_t>(t), c[0], c[1], c[2]);
      }, 4096);
      file.write(block.get(), kRecord * static_cast<std::size_t>(count));
    }
  } else {
    std::size_t filled = 0;
    for (Id c = 0; c < cells; ++c) {
      const std::uint64_t b = mesh.cell_begin(c), e = mesh.cell_end(c);
      for (std::uint64_t k = b + 1; k + 1 < e; ++k) {
        if (filled == kPerBlock) file.write(block.get(), kRecord * filled), filled = 0;
        record(block.get() + kRecord * filled++, conn[b], conn[k], conn[k + 1]);
      }
    }
    file.write(block.get(), kRecord * filled);
  }
  file.commit();
}

}  // namespace keymesh::io
