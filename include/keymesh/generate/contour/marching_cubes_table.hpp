#pragma once
// The marching cubes case table, built at start-up from one rule instead of
// being typed in: on a cube face whose diagonal corners disagree (an
// ambiguous face), the *inside* corners (value >= iso) are separated. The rule
// depends on the face alone, so two cubes sharing a face always agree and the
// surface has no cracks; it also gives, case by case, the same number of
// triangles as VTK's table (vtkMarchingCubes / vtkFlyingEdges3D), which
// tests/vtk checks on real data.
//
// Corner c of a cube sits at (c & 1, (c >> 1) & 1, (c >> 2) & 1) (VTK's
// voxel order); case bit c is set when corner c is inside. Each polygon traced
// through the cut edges is oriented with its normal pointing to the outside
// (towards lower values) and fanned into triangles.
#include <array>
#include <cstdint>

namespace keymesh::generate {

struct CubeEdge {
  std::uint8_t corner0, corner1;  // corner0 < corner1; they differ along `axis`
  std::uint8_t axis;              // 0 = x, 1 = y, 2 = z
  std::uint8_t dx, dy, dz;        // offset of corner0 from the cube's first corner
};

struct MarchingCubesTable {
  std::array<CubeEdge, 12> edges;
  std::array<std::uint8_t, 256> triangle_count;      // 0..5
  std::array<std::array<std::uint8_t, 15>, 256> triangle_edges;  // 3 edge ids per triangle
};

// Built once (thread-safe static initialisation).
//
// With `reversed_axes`: the table for a grid whose x and z are the caller's z
// and x (a C-order numpy array contoured without a copy, its output mirrored
// back). Each case gets the triangles the caller's frame gives the mirrored
// case, mirrored and wound the other way (a mirror turns orientation), so the
// caller receives the same triangles from either memory order.
const MarchingCubesTable& marching_cubes_table(bool reversed_axes = false);

}  // namespace keymesh::generate
