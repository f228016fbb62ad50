#pragma once
// Marching cubes with scikit-image's conventions (skimage.measure.marching_cubes,
// method="lorensen", or method="lewiner" with Mc33Tables set), welded by
// KEY-REDUCE: what keymesh.marching_cubes runs.
//
// The library's contour() and this generator find the same points (one per
// grid edge whose samples straddle the level) but differ in the details a
// scikit-image user depends on, so this is a generator of its own:
//  - inside means value > level (contour: >=); the volume is float32;
//  - a point's position is the "centre of mass" of the edge's two corners
//    weighted by 1 / (eps + |value - level|) (the linear interpolation,
//    rounded the way scikit-image rounds it);
//  - normals: every triangle corner adds, in the cube that made it, the
//    one-sided differences at the edge's two corners weighted as above (the
//    difference taken at the corner scikit-image takes it from, see the .cpp);
//    the float32 sum is normalised (contour's gradient normals are central
//    differences);
//  - values: the largest (max - min) of the cubes whose triangles use the point;
//  - the triangulation of each cube is a caller-given classic case table
//    (ClassicTable, edge numbering below): scikit-image's own table gives its
//    faces exactly; classic_table() gives keymesh's (same points and
//    polygons, other diagonals in some cubes); or Marching Cubes 33
//    (Mc33Tables): ambiguous faces and interiors tested, and a point at the
//    weighted centre of some cubes (its normal the corners' weighted
//    gradients), keyed after the edges;
//  - step: cubes of step^3 voxels; mask: a cube is kept when the mask is set
//    at its far corner (+step on every axis), scikit-image's rule.
//
// The triangle corners are keyed by their coarse grid edge and welded by
// KEY-REDUCE (dense plan). Points are then numbered by their first use in
// the scan (z slowest, x fastest, triangles in table order), which is the
// order in which scikit-image creates them, and every point's normal sums
// its corners' contributions in float32 in that order: the arrays are
// scikit-image's, bit for bit, whatever the thread count.
//
// Coordinates: the volume is C-ordered with shape (n0, n1, n2); x runs along
// axis 2 (fastest), z along axis 0. Output points and normals are in array
// axis order (axis 0 first), spacing 1 (the caller scales).
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "keymesh/core/types.hpp"

namespace keymesh::generate {

// Row c: the triangles of case c (bit k set when corner k is inside) as
// triples of edge ids, -1 after the last. Corners 0..3 go round the z = 0
// face, (0,0,0) (1,0,0) (1,1,0) (0,1,0), corners 4..7 the same at z = 1;
// edges 0..3 join corners k and k+1 (mod 4) at z = 0, 4..7 the same at
// z = 1, 8..11 join corner k to k + 4 (Lorensen & Cline / Bourke numbering).
using ClassicTable = std::array<std::array<std::int8_t, 16>, 256>;

// keymesh's case table (marching_cubes_table.hpp) in that numbering and
// corner order, triangles wound as scikit-image's table winds them.
ClassicTable classic_table();

// Lewiner et al.'s Marching Cubes 33 tables, by the names scikit-image gives
// them (CASES, TILING1 ... TILING14, TEST3 ... TEST13, SUBCONFIG13): int8
// arrays with their shapes. keymesh ships no copy; the Python module reads
// scikit-image's at run time. Edge id 12 in a tiling is the cube's centre
// point.
struct Mc33Array {
  std::vector<std::int8_t> data;
  std::vector<int> shape;
};
using Mc33Tables = std::map<std::string, Mc33Array>;

struct ClassicMarchingCubesOptions {
  double level = 0;
  int step = 1;                         // >= 1
  const std::uint8_t* mask = nullptr;   // same shape as the volume, C order; nonzero = set
  bool descent = true;                  // scikit-image's gradient_direction="descent": faces reversed
  // Set: scikit-image's method="lewiner" (Marching Cubes 33: ambiguous faces
  // and cube interiors tested, centre points added) with these tables; the
  // classic table is then not used. InputError when a table is missing or
  // out of range.
  const Mc33Tables* mc33 = nullptr;
  // Per-point history (docs/HISTORY.md): ClassicMarchingCubes::history_key
  // and history_t.
  bool history = false;
};

struct ClassicMarchingCubes {
  std::vector<float> vertices;          // (V, 3), axis 0 first
  std::vector<std::int32_t> faces;      // (F, 3)
  std::vector<float> normals;           // (V, 3), unit or zero, axis 0 first
  std::vector<float> values;            // (V,)
  // With options.history, per point, in the frame keymesh.contour gives the
  // same array (array axis A is its axis A, N = n0 n1 n2): an edge point's
  // 3 * (i0 + n0 (i1 + n1 i2)) + A, (i0, i1, i2) the lower end of its edge
  // (of step samples) along array axis A, and t the float32 nearest the
  // crossing's fraction of it among those giving the vertex back as
  // float32(i_A + step * double(t)); a cube centre (Marching Cubes 33)
  // 3N + (i0 + n0 (i1 + n1 i2)) of its lowest corner, t 0.5.
  std::vector<std::uint64_t> history_key;
  std::vector<float> history_t;
};

// Throws InputError for a dimension below 2 or step < 1, LimitError past
// 2^31 - 1 points or triangle corners (scikit-image's int32 faces).
ClassicMarchingCubes classic_marching_cubes(const float* volume, std::array<Id, 3> shape,
                                            const ClassicTable& table,
                                            const ClassicMarchingCubesOptions& options);

}  // namespace keymesh::generate
