#include "keymesh/mesh/fields.hpp"
#include "keymesh/mesh/cell_tables.hpp"
#include "keymesh/generate/unstructured/tetrahedralize.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <limits>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"

namespace keymesh::generate {

namespace {

// Hexahedron corners are numbered here by bits: corner c sits at
// (c & 1, (c >> 1) & 1, (c >> 2) & 1) in the cell's parametric cube.
// The even split's central tet stands on the corners with an even number of
// set bits (0, 3, 5, 6), the odd split's on the others (1, 2, 4, 7); each
// remaining corner is cut off with its three neighbours.
constexpr std::uint8_t kSplit[2][5][4] = {
    {{0, 3, 5, 6}, {1, 0, 3, 5}, {2, 0, 6, 3}, {4, 0, 5, 6}, {7, 3, 6, 5}},
    {{1, 2, 4, 7}, {0, 1, 4, 2}, {3, 1, 2, 7}, {5, 1, 7, 4}, {6, 2, 4, 7}},
};

// The splits with every tet positively oriented on the unit cube.
FiveTetSplits oriented_splits() {
  FiveTetSplits s{};
  for (int parity = 0; parity < 2; ++parity)
    for (int t = 0; t < 5; ++t) {
      float p[4][3];
      for (int v = 0; v < 4; ++v) {
        const int c = kSplit[parity][t][v];
        s.tet[parity][t][v] = static_cast<std::uint8_t>(c);
        p[v][0] = float(c & 1);
        p[v][1] = float((c >> 1) & 1);
        p[v][2] = float((c >> 2) & 1);
      }
      if (tet_volume(p[0], p[1], p[2], p[3]) < 0) std::swap(s.tet[parity][t][2], s.tet[parity][t][3]);
    }
  return s;
}

const FiveTetSplits& splits() { return five_tet_splits(); }

Id checked_mul(Id a, Id b, const char* what) {
  if (a != 0 && b > std::numeric_limits<Id>::max() / a)
    throw LimitError(std::string("tetrahedralize: ") + what + " overflow 64 bits");
  return a * b;
}

// Hexahedron corners in bit order and its faces (mesh/cell_tables.hpp).
constexpr const auto& kFaces = cells::kHexFaceCycle;

// The diagonal of face f that the split of `parity` cuts: the two face
// corners whose bit count has that parity.
std::array<int, 2> face_diagonal(int f, int parity) {
  std::array<int, 2> d{};
  int n = 0;
  for (int c : kFaces[f])
    if ((std::popcount(unsigned(c)) & 1) == parity) d[n++] = c;
  return d;
}

}  // namespace

const FiveTetSplits& five_tet_splits() {
  static const FiveTetSplits s = oriented_splits();
  return s;
}

UnstructuredGrid grid_points(const ImageGrid& grid) {
  const Id nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  const Id points = checked_mul(checked_mul(nx, ny, "point count"), nz, "point count");
  checked_mul(points, 3 * Id(sizeof(float)), "point coordinates");
  UnstructuredGrid out;
  parallel::resize_fresh(out.points, static_cast<std::size_t>(3 * points));
  const Id nxy = nx * ny;
  const GridPoints where{nx, nxy, {grid.origin[0], grid.origin[1], grid.origin[2]},
                         {grid.spacing[0], grid.spacing[1], grid.spacing[2]}};
  parallel::for_each(points, [&](Id p) { where.position(p, &out.points[3 * p]); });
  Field f{grid.name, 1, {}};
  parallel::resize_fresh(f.values, static_cast<std::size_t>(points));
  visit_scalars(grid, [&](const auto* samples) {
    parallel::for_each(points, [&](Id p) { f.values[p] = static_cast<float>(samples[p]); });
  });
  out.point_fields.push_back(std::move(f));
  return out;
}

void check_tetrahedralize5_input(const ImageGrid& grid) {
  const Id nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  for (int a = 0; a < 3; ++a)
    if (grid.dims[a] < 2)
      throw InputError("tetrahedralize: grid has " + std::to_string(grid.dims[a]) + " point(s) along axis " + "xyz"[a] +
                       " (need at least 2)");
  const Id points = checked_mul(checked_mul(nx, ny, "point count"), nz, "point count");
  const Id voxels = checked_mul(checked_mul(nx - 1, ny - 1, "voxel count"), nz - 1, "voxel count");
  checked_mul(voxels, 20, "tet corner count");
  checked_mul(points, 3 * Id(sizeof(float)), "point coordinates");
}

UnstructuredGrid tetrahedralize5(const ImageGrid& grid) {
  check_tetrahedralize5_input(grid);
  const Id nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  const Id points = nx * ny * nz;
  const Id corners = 20 * (nx - 1) * (ny - 1) * (nz - 1);

  UnstructuredGrid out = grid_points(grid);
  out.uniform_type = CellType::Tetra;
  out.connectivity = IndexArray::for_ids(static_cast<std::uint64_t>(points), static_cast<std::size_t>(corners));
  const Id nxy = nx * ny;
  // A mirrored grid (an odd number of negative spacings) turns every tet inside out.
  const bool mirrored = (grid.spacing[0] < 0) != ((grid.spacing[1] < 0) != (grid.spacing[2] < 0));
  Id corner_offset[8];
  for (int c = 0; c < 8; ++c) corner_offset[c] = (c & 1) + nx * ((c >> 1) & 1) + nxy * ((c >> 2) & 1);
  const auto& split = splits();
  out.connectivity.visit_mut([&](auto ids) {
    using I = typename decltype(ids)::value_type;
    const Id rows = (ny - 1) * (nz - 1);
    parallel::for_each(rows, [&](Id r) {
      const Id j = r % (ny - 1), k = r / (ny - 1);
      for (Id i = 0; i < nx - 1; ++i) {
        const Id v = i + (nx - 1) * r;
        const Id base = i + nx * j + nxy * k;
        const int parity = static_cast<int>((i + j + k) & 1);
        I* o = ids.data() + 20 * v;
        for (int t = 0; t < 5; ++t) {
          const auto& tet = split.tet[parity][t];
          o[4 * t + 0] = static_cast<I>(base + corner_offset[tet[0]]);
          o[4 * t + 1] = static_cast<I>(base + corner_offset[tet[1]]);
          o[4 * t + 2] = static_cast<I>(base + corner_offset[mirrored ? tet[3] : tet[2]]);
          o[4 * t + 3] = static_cast<I>(base + corner_offset[mirrored ? tet[2] : tet[3]]);
        }
      }
    }, 4);
  });
  return out;
}

namespace {

// Face adjacency: faces sorted by their sorted corner ids; equal runs are
// shared faces. next[c] lists (neighbour, (face of c, face of neighbour)).
using FaceNeighbours = std::vector<std::vector<std::pair<Id, std::pair<int, int>>>>;

FaceNeighbours face_neighbours(const std::vector<std::array<std::uint64_t, 8>>& corner) {
  const Id cells = static_cast<Id>(corner.size());
  struct FaceRef {
    std::array<std::uint64_t, 4> key;
    Id cell;
    int face;
  };
  std::vector<FaceRef> faces;
  faces.reserve(static_cast<std::size_t>(6 * cells));
  for (Id c = 0; c < cells; ++c)
    for (int f = 0; f < 6; ++f) {
      FaceRef r{{}, c, f};
      for (int v = 0; v < 4; ++v) r.key[v] = corner[c][kFaces[f][v]];
      std::sort(r.key.begin(), r.key.end());
      faces.push_back(r);
    }
  std::sort(faces.begin(), faces.end(), [](const FaceRef& a, const FaceRef& b) {
    return a.key != b.key ? a.key < b.key : (a.cell != b.cell ? a.cell < b.cell : a.face < b.face);
  });
  FaceNeighbours next(static_cast<std::size_t>(cells));
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t e = i + 1;
    while (e < faces.size() && faces[e].key == faces[i].key) ++e;
    if (e - i > 2)
      throw InputError("tetrahedralize --scheme 5: face shared by " + std::to_string(e - i) + " cells (cells " +
                       std::to_string(faces[i].cell) + ", " + std::to_string(faces[i + 1].cell) + ", " +
                       std::to_string(faces[i + 2].cell) + ")");
    if (e - i == 2) {
      next[faces[i].cell].push_back({faces[i + 1].cell, {faces[i].face, faces[i + 1].face}});
      next[faces[i + 1].cell].push_back({faces[i].cell, {faces[i + 1].face, faces[i].face}});
    }
    i = e;
  }
  return next;
}

// Breadth-first 2-colouring: a neighbour takes the split whose diagonal on
// the shared face is the one this cell already cuts.
std::vector<int> split_parities(const std::vector<std::array<std::uint64_t, 8>>& corner, const FaceNeighbours& next) {
  const Id cells = static_cast<Id>(corner.size());
  auto diagonal_ids = [&](Id c, int f, int parity) {
    const auto d = face_diagonal(f, parity);
    std::array<std::uint64_t, 2> ids{corner[c][d[0]], corner[c][d[1]]};
    std::sort(ids.begin(), ids.end());
    return ids;
  };
  std::vector<int> parity(static_cast<std::size_t>(cells), -1);
  std::vector<Id> queue;
  for (Id seed = 0; seed < cells; ++seed) {
    if (parity[seed] >= 0) continue;
    parity[seed] = 0;
    queue.assign(1, seed);
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const Id c = queue[q];
      for (const auto& [n, ff] : next[c]) {
        const auto want = diagonal_ids(c, ff.first, parity[c]);
        int p = -1;
        for (int cand = 0; cand < 2; ++cand)
          if (diagonal_ids(n, ff.second, cand) == want) p = cand;
        if (p < 0 || (parity[n] >= 0 && parity[n] != p))
          throw InputError("tetrahedralize --scheme 5: cells " + std::to_string(c) + " and " + std::to_string(n) +
                           " cannot both be split into 5 tets with matching diagonals on their shared face "
                           "(the cells do not 2-colour like a structured grid)");
        if (parity[n] < 0) {
          parity[n] = p;
          queue.push_back(n);
        }
      }
    }
  }
  return parity;
}

}  // namespace

UnstructuredGrid tetrahedralize5(const UnstructuredGrid& hexes) {
  hexes.validate("tetrahedralize input");
  const Id cells = hexes.num_cells();
  const auto corner = cells::hex_corners(hexes, "tetrahedralize --scheme 5");
  const std::vector<int> parity = split_parities(corner, face_neighbours(corner));
  UnstructuredGrid out;
  out.points = hexes.points;
  out.point_fields = hexes.point_fields;
  out.uniform_type = CellType::Tetra;
  out.connectivity =
      IndexArray::for_ids(static_cast<std::uint64_t>(hexes.num_points()), static_cast<std::size_t>(20 * cells));
  const auto& split = splits();
  const float* P = out.points.data();
  parallel::for_each(cells, [&](Id c) {
    for (int t = 0; t < 5; ++t) {
      std::uint64_t v[4];
      for (int k = 0; k < 4; ++k) v[k] = corner[c][split.tet[parity[c]][t][k]];
      // The cell may be mirrored (left-handed corner order): orient by volume.
      if (tet_volume(P + 3 * v[0], P + 3 * v[1], P + 3 * v[2], P + 3 * v[3]) < 0) std::swap(v[2], v[3]);
      for (int k = 0; k < 4; ++k) out.connectivity.set(static_cast<std::size_t>(20 * c + 4 * t + k), v[k]);
    }
  });
  out.cell_fields = repeat_cell_fields(hexes.cell_fields, cells, 5);
  return out;
}

}  // namespace keymesh::generate
