#pragma once
// The label map as the label generators read it (internal to src/generate):
// each sample replaced by the index of its label among the volume's sorted
// distinct labels, padded with one layer of background all round so that no
// generator has a border case and every region's surface closes.
#include <array>
#include <cstdint>
#include <vector>

#include "keymesh/generate/labels.hpp"
#include "keymesh/mesh/image_grid.hpp"

namespace keymesh::generate::detail {

using LabelIndex = std::uint16_t;  // < kMaxDistinctLabels

struct LabelVolume {
  std::array<Id, 3> dims{};   // padded: grid dims + 2
  Id nxy = 0, n = 0;          // padded sizes
  std::array<double, 3> origin{}, spacing{};  // of the unpadded grid
  std::vector<LabelIndex> index;         // n label indices, x fastest
  std::vector<std::int64_t> values;      // label value of every index, increasing
  LabelIndex background = 0;             // index of the background value
  Id distinct_in_grid = 0;               // distinct values the grid holds
  // Selected labels (indices, increasing) with their voxel counts and the
  // bounding box of their voxels in padded coordinates, [lo, hi] inclusive.
  std::vector<LabelIndex> selected;
  std::vector<Id> voxels;
  std::vector<std::array<Id, 6>> box;

  Id at(Id i, Id j, Id k) const { return i + j * dims[0] + k * nxy; }
  // Position of padded grid point (i, j, k) along axis a.
  double coord(int a, double i) const { return origin[a] + spacing[a] * (i - 1.0); }
};

// Throws InputError naming grid.name-less context ("labels: ...") for float
// samples, labels past kMaxLabelMagnitude, too many distinct labels, a
// selected label the volume does not hold or a selected background.
LabelVolume scan_labels(const ImageGrid& grid, const LabelOptions& options);

// Output of a label generator before smoothing: the welded mesh plus what
// smoothing needs to know about every point.
struct LabelSurface {
  SurfaceMesh mesh;  // points, triangles, cell fields boundary_labels (and label)
  // Per triangle: the pair of label indices across it (smaller first) packed
  // as first << 16 | second.
  std::vector<std::uint32_t> pair;
  // Triangles come in pairs, quads (C00, C10, C11), (C00, C11, C01) (surface
  // nets): the smoothing stencil takes the quads' sides, not their diagonals.
  bool quads = false;
  // Per point: a junction (three or more labels meet: triple lines and
  // corners), and the axes along which it lies on the padded border (bit a:
  // its coordinate along a is fixed by the padding plane).
  std::vector<std::uint8_t> junction;
  std::vector<std::uint8_t> border_axes;
  // Surface nets: the box a point must stay in (its cell), as the cell
  // centre; half a spacing either side. Empty for discrete MC.
  std::vector<float> cell_centre;
};

// Appends the parts (their own points each) to `out`, in order.
void append_surfaces(std::vector<LabelSurface>& parts, LabelSurface& out);

LabelSurface surface_nets(const LabelVolume& volume, bool per_label, LabelStats& stats);
LabelSurface discrete_marching_cubes(const LabelVolume& volume, bool per_label, LabelStats& stats);

// Smooths the surface's points in place (label_smoothing.cpp): Jacobi
// iterations over neighbour lists built by KEY-REDUCE.
void smooth_label_surface(LabelSurface& surface, const LabelVolume& volume, LabelMethod method, int iterations,
                          double relaxation);

}  // namespace keymesh::generate::detail
