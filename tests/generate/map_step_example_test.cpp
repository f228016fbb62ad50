// The worked example of docs/ARCHITECTURE.md ("A new generator is its map
// step"): the face centres of a grid of hexahedra, one point per distinct
// face, written as a map step over the shared layers. The test checks it
// against tetrahedralize --scheme 24, whose face-centre points it must equal
// bit for bit, so the example in the notes cannot rot.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "keymesh/generate/unstructured/tetrahedralize.hpp"
#include "keymesh/keyreduce/weld.hpp"
#include "keymesh/mesh/cell_tables.hpp"
#include "keymesh/mesh/fields.hpp"
#include "keymesh/mesh/keys.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh {
namespace {

// --- the example (docs/ARCHITECTURE.md quotes this function) ---
UnstructuredGrid face_centres(const UnstructuredGrid& hexes) {
  // Input topology: every cell's corners in bit order, and the key of a
  // quad face (its smallest corner and the corner opposite it).
  const auto corner = cells::hex_corners(hexes, "face_centres");
  const EdgeKeys ek = EdgeKeys::for_points(hexes.num_points(), "face_centres");
  auto face = [&](Id pair, std::uint64_t ids[4]) {  // pair = 6 * cell + face
    for (int k = 0; k < 4; ++k) ids[k] = corner[pair / 6][cells::kHexFaceCycle[pair % 6][k]];
  };
  // Map: every (cell, face) pair emits the key of the face it names.
  const Id pairs = 6 * hexes.num_cells();
  std::vector<std::uint64_t> keys(static_cast<std::size_t>(pairs));
  parallel::for_each(pairs, [&](Id pair) {
    std::uint64_t ids[4];
    face(pair, ids);
    keys[pair] = ek.quad(ids);
  });
  // Weld: KEY-REDUCE groups the pairs by key (sort plan); a face shared by
  // two cells is one group, whose first pair stands for it.
  keyreduce::WeldSpec<std::uint64_t> spec;
  spec.plan = keyreduce::WeldPlan::Sort;
  spec.key_bits = ek.key_bits();
  std::vector<std::uint32_t> first;
  const auto groups = keyreduce::weld(keys.data(), pairs, spec, [](Id, float*) {}, {nullptr, &first});
  // Reduce: one point per group, its position and fields the mean of the
  // face's corners.
  const Id faces = groups.num_groups();
  UnstructuredGrid out;
  out.points.resize(static_cast<std::size_t>(3 * faces));
  out.point_fields = new_point_fields(hexes.point_fields, faces);
  parallel::for_each(faces, [&](Id g) {
    std::uint64_t ids[4];
    face(first[g], ids);
    mean_position(hexes.points.data(), ids, 4, &out.points[3 * g]);
    average_point_fields(hexes.point_fields, out.point_fields, g, ids, 4);
  });
  return out;
}
// --- end of the example ---

// A 3 x 2 x 2 box of hexahedra (VTK order) with uneven spacing and a field.
UnstructuredGrid box() {
  const Id nx = 4, ny = 3, nz = 3;
  UnstructuredGrid g;
  Field f{"temperature", 1, {}};
  for (Id k = 0; k < nz; ++k)
    for (Id j = 0; j < ny; ++j)
      for (Id i = 0; i < nx; ++i) {
        g.points.insert(g.points.end(), {float(i * i) * 0.5f, float(j) + 0.1f * float(i), float(k) * 1.25f});
        f.values.push_back(float(i + 10 * j + 100 * k));
      }
  g.point_fields.push_back(f);
  g.uniform_type = CellType::Hexahedron;
  std::vector<std::uint64_t> ids;
  const int hex[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (Id k = 0; k + 1 < nz; ++k)
    for (Id j = 0; j + 1 < ny; ++j)
      for (Id i = 0; i + 1 < nx; ++i)
        for (const auto& d : hex) ids.push_back(static_cast<std::uint64_t>((i + d[0]) + nx * ((j + d[1]) + ny * (k + d[2]))));
  g.connectivity = IndexArray::for_ids(static_cast<std::uint64_t>(nx * ny * nz), ids.size());
  for (std::size_t c = 0; c < ids.size(); ++c) g.connectivity.set(c, ids[c]);
  return g;
}

TEST(MapStepExample, FaceCentresEqualScheme24sFacePoints) {
  const UnstructuredGrid hexes = box();
  const UnstructuredGrid centres = face_centres(hexes);
  // Distinct faces of a 3 x 2 x 2 box: x-faces 4*2*2, y-faces 3*3*2, z-faces 3*2*3.
  const Id faces = 16 + 18 + 18;
  ASSERT_EQ(centres.num_points(), faces);
  const UnstructuredGrid tets = generate::tetrahedralize24(hexes);
  const Id N = hexes.num_points();
  ASSERT_EQ(tets.num_points(), N + faces + hexes.num_cells());
  for (Id p = 0; p < faces; ++p)
    for (int x = 0; x < 3; ++x) EXPECT_EQ(centres.points[3 * p + x], tets.points[3 * (N + p) + x]) << p;
  const Field* t = tets.find_point_field("temperature");
  ASSERT_NE(t, nullptr);
  for (Id p = 0; p < faces; ++p) EXPECT_EQ(centres.point_fields[0].values[p], t->values[N + p]) << p;
}

}  // namespace
}  // namespace keymesh
