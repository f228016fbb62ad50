#include "keymesh/mesh/unstructured_grid.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"

namespace keymesh {

IndexArray IndexArray::for_ids(std::uint64_t max_id_exclusive, std::size_t n) {
  IndexArray a;
  a.wide_ = max_id_exclusive > std::uint64_t(UINT32_MAX) + 1;
  if (a.wide_) parallel::resize_fresh(a.v64_, n);
  else parallel::resize_fresh(a.v32_, n);
  return a;
}

int cell_type_size(CellType t) {
  switch (t) {
    case CellType::Vertex: return 1;
    case CellType::Line: return 2;
    case CellType::Triangle: return 3;
    case CellType::Polygon: return 0;
    case CellType::Quad: return 4;
    case CellType::Tetra: return 4;
    case CellType::Voxel: return 8;
    case CellType::Hexahedron: return 8;
    case CellType::Wedge: return 6;
    case CellType::Pyramid: return 5;
  }
  return 0;
}

std::string cell_type_name(std::uint8_t vtk_type) {
  switch (static_cast<CellType>(vtk_type)) {
    case CellType::Vertex: return "vertex";
    case CellType::Line: return "line";
    case CellType::Triangle: return "triangle";
    case CellType::Polygon: return "polygon";
    case CellType::Quad: return "quad";
    case CellType::Tetra: return "tetra";
    case CellType::Voxel: return "voxel";
    case CellType::Hexahedron: return "hexahedron";
    case CellType::Wedge: return "wedge";
    case CellType::Pyramid: return "pyramid";
  }
  return "type " + std::to_string(vtk_type);
}

bool UnstructuredGrid::all_cells_are(CellType t) const {
  if (cell_types.empty()) return uniform_type == t || num_cells() == 0;
  for (std::uint8_t c : cell_types)
    if (c != static_cast<std::uint8_t>(t)) return false;
  return true;
}

namespace {
bool known_type(std::uint8_t t) {
  switch (static_cast<CellType>(t)) {
    case CellType::Vertex:
    case CellType::Line:
    case CellType::Triangle:
    case CellType::Polygon:
    case CellType::Quad:
    case CellType::Tetra:
    case CellType::Voxel:
    case CellType::Hexahedron:
    case CellType::Wedge:
    case CellType::Pyramid: return true;
  }
  return false;
}
}  // namespace

void UnstructuredGrid::validate(const std::string& what, bool check_ids) const {
  auto fail = [&](const std::string& m) { throw InputError(what + ": " + m); };
  if (points.size() % 3 != 0) fail("point coordinates are not a multiple of 3");
  const std::uint64_t np = points.size() / 3;
  // 1e39, inf and nan all end up non-finite as float: refused by name, never written on.
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!std::isfinite(points[i]))
      fail("point " + std::to_string(i / 3) + " has a non-finite coordinate " + "xyz"[i % 3] + " = " +
           std::to_string(points[i]));
  Id nc = 0;
  if (offsets.empty()) {
    const int k = cell_type_size(uniform_type);
    if (k == 0) fail("uniform cell type " + cell_type_name(std::uint8_t(uniform_type)) + " needs offsets");
    if (connectivity.size() % std::size_t(k) != 0)
      fail("connectivity length " + std::to_string(connectivity.size()) + " is not a multiple of " +
           std::to_string(k) + " (" + cell_type_name(std::uint8_t(uniform_type)) + " cells)");
    nc = Id(connectivity.size() / std::size_t(k));
  } else {
    nc = Id(offsets.size()) - 1;
    if (offsets.front() != 0) fail("offsets do not start at 0");
    if (offsets.back() != connectivity.size())
      fail("last offset " + std::to_string(offsets.back()) + " does not match connectivity length " +
           std::to_string(connectivity.size()));
    for (Id c = 0; c < nc; ++c)
      if (offsets[c + 1] < offsets[c]) fail("offsets decrease at cell " + std::to_string(c));
  }
  if (!cell_types.empty() && Id(cell_types.size()) != nc)
    fail("cell type count " + std::to_string(cell_types.size()) + " differs from cell count " + std::to_string(nc));
  if (!cell_types.empty() || !offsets.empty()) {
    for (Id c = 0; c < nc; ++c) {
      const std::uint8_t t = cell_type(c);
      if (!known_type(t)) fail("cell " + std::to_string(c) + " has unsupported " + cell_type_name(t));
      const int k = cell_type_size(static_cast<CellType>(t));
      const std::uint64_t n = cell_end(c) - cell_begin(c);
      if (k != 0 ? n != std::uint64_t(k) : n < 3)
        fail("cell " + std::to_string(c) + " (" + cell_type_name(t) + ") has " + std::to_string(n) + " corners");
    }
  }
  // The largest id, found in parallel (82.9 M tets are 331 M ids); only
  // when it is out of range is the first offender looked for.
  const std::uint64_t max_id = !check_ids ? 0 : connectivity.visit([&](auto ids) {
    const Id n = static_cast<Id>(ids.size());
    const int chunks = parallel::chunk_count(n, 1 << 16);
    std::vector<std::uint64_t> chunk_max(static_cast<std::size_t>(std::max(chunks, 1)), 0);
    parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
      std::uint64_t m = 0;
      for (Id i = b; i < e; ++i) m = std::max<std::uint64_t>(m, ids[i]);
      chunk_max[c] = m;
    });
    return *std::max_element(chunk_max.begin(), chunk_max.end());
  });
  if (!connectivity.empty() && max_id >= np)
    connectivity.visit([&](auto ids) {
      for (std::size_t i = 0; i < ids.size(); ++i)
        if (std::uint64_t(ids[i]) >= np)
          fail("point id " + std::to_string(std::uint64_t(ids[i])) + " at connectivity[" + std::to_string(i) +
               "] is out of range (" + std::to_string(np) + " points)");
    });
  for (const auto& f : point_fields)
    if (f.components < 1 || f.values.size() != np * std::uint64_t(f.components))
      fail("point field '" + f.name + "' has " + std::to_string(f.values.size()) + " values for " +
           std::to_string(np) + " points");
  for (const auto& f : cell_fields)
    if (f.components < 1 || f.values.size() != std::uint64_t(nc) * std::uint64_t(f.components))
      fail("cell field '" + f.name + "' has " + std::to_string(f.values.size()) + " values for " +
           std::to_string(nc) + " cells");
}

}  // namespace keymesh
