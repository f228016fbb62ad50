#pragma once
// Surfaces of a label map (a segmentation: one integer region id per grid
// point), welded by history keys: the map step of a generator writes keys
// and KEY-REDUCE (partition_dense) connects them.
//
// The volume is treated as padded with one layer of background all round,
// so every region's surface is closed, also where a label touches the grid's
// border (vtkDiscreteFlyingEdges3D leaves those surfaces open there).
// Labels not selected (LabelOptions::labels) count as background.
//
// Methods:
//  - SurfaceNets (default): the dual of the label boundaries. A point per
//    grid cell (the cube between 8 samples) whose corners carry more than one
//    label, keyed by the cell, placed at the cell's centre before smoothing;
//    a quad (two triangles) per grid edge whose two end labels differ, keyed
//    by that edge, its corners the 4 cells around the edge. Every interface
//    is written once; points are shared by every label meeting in the cell.
//    Unsmoothed, a region's surface is the boundary of the union of its
//    voxels (unit cubes centred on its grid points): its enclosed volume is
//    the voxel count times the voxel volume.
//  - DiscreteMarchingCubes: each label's indicator (value == label)
//    contoured at 0.5 by keymesh's marching cubes (generate/contour.hpp):
//    points at edge midpoints keyed by the edge, so labels sharing an edge
//    share its point; one label gives the points and triangles of
//    vtkDiscreteFlyingEdges3D. An interface is written once per side.
//
// Cell fields:
//  - boundary_labels (2 components): the two labels across the face,
//    smaller first (PyVista's contour_labels convention).
//  - label (with per_label or DiscreteMarchingCubes): the region whose
//    surface the face belongs to.
// Orientation: without per_label, surface nets faces have their normal
// pointing from boundary_labels[0] (smaller) to boundary_labels[1]; in
// per-label surfaces and discrete MC, normals point out of `label`.
//
// per_label: each selected label's closed surface, with its own points
// (labels in increasing order). Surface nets then gives a cell one point per
// loop the label's boundary makes on the cell's faces (per polygon of the
// marching cubes table, whose face rule keeps the label's voxels apart across
// face diagonals), so each surface is the dual of the label's discrete
// marching cubes surface and a closed 2-manifold. The label's voxels count
// as 6-connected (faces only), the rest as 26-connected, with one exception
// the marching cubes table makes (VTK's as well): a cube whose only outside
// corners are the two ends of a body diagonal has its six inside corners
// joined through the cube (a ring 6-connectivity would leave open). So the
// Euler characteristic of a label's surface is, for both methods,
//   2 x (skimage.measure.euler_number(region, connectivity=1) + R)
// with R the number of such cubes (region padded with background).
// A cell with several loops places each loop's point at the centroid of its
// cut edges' midpoints instead of the cell centre. Where both cells of an
// ambiguous face (the label on one diagonal) join the face's two arcs into
// one loop, the quads of the face's four edges would all meet on one dual
// edge; there each arc gets a face point (keyed by the face and the arc, a
// quarter spacing from the arc's label corner), which splits that side of
// the two quads of its arc, and those polygons are fanned from it.
// Checked on white-noise label maps (tests/python/test_labels.py, 12 seeds):
// every per-label surface of both methods closed, 2-manifold, Euler as above.
//
// Coarsening (coarsen): every point gets a coarser key, surface nets the
// 2x2x2 block of cells holding its cell (face points: the face's cell),
// discrete MC the nearest grid point (a midpoint's lower edge end); per
// label, labels never share one. One KEY-REDUCE merges the points of a key,
// averaging their (smoothed) positions in increasing index; faces left with
// fewer than three distinct points are dropped, and faces of one label pair
// on the same three points cancel by orientation (|net| copies of the
// winning one are kept, first in face order). Each kept face keeps its
// label pair (and label): the two labels across the grid edge it came from.
// Guaranteed: every label's faces, oriented out of it (network: faces whose
// pair holds it, flipped where it is the larger; per label and discrete MC:
// faces of `label`), still form a closed 2-cycle (every directed edge used
// as often as its reverse), since merging points and dropping collapsed or
// cancelling faces keeps a cycle a cycle. Not guaranteed: 2-manifoldness
// (an edge may gain four faces where a region is thinner than a block) and
// the Euler characteristic.
//
// Guarantees: deterministic, bit-identical output at any thread count.
// Refused (InputError, naming the volume): float samples, labels that are
// not exactly representable as float32 (|v| > 2^24), more than
// kMaxDistinctLabels distinct values, fewer than 1 point along an axis.
#include <cstdint>
#include <vector>

#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::generate {

enum class LabelMethod { SurfaceNets, DiscreteMarchingCubes };

// Distinct values a volume may hold, background included (label indices are
// 16-bit inside the generator).
constexpr Id kMaxDistinctLabels = 65536;
// Largest |label|: boundary_labels is a float32 field.
constexpr std::int64_t kMaxLabelMagnitude = 16777216;

struct LabelOptions {
  LabelMethod method = LabelMethod::SurfaceNets;
  std::vector<std::int64_t> labels;  // labels to extract; empty: every label but the background
  std::int64_t background = 0;
  bool per_label = false;
  // Smoothing of the welded mesh (generate/label_smoothing.hpp): 0 = off.
  int smooth_iterations = 16;
  double relaxation = 0.5;
  // Coarsening after smoothing (see the header comment): points merged by a
  // coarser key, faces that collapse dropped, label pairs kept.
  bool coarsen = false;
  // Per-point history (docs/HISTORY.md): the point field history_t and,
  // through contour_labels()'s history_key, each point's element of the
  // padded grid (discrete MC: its edge 3 * point + axis; surface nets:
  // 16 * the cell's first corner + its loop or face point). Keys and t do
  // not depend on smoothing (the unsmoothed point's), threads or slabs.
  // Refused (InputError) with coarsen: a coarse point merges several.
  bool history = false;
};

struct LabelPairCount {
  std::int64_t first = 0, second = 0;  // first < second
  Id points = 0;                       // distinct points of the faces of this pair
  Id faces = 0;                        // triangles
};

struct LabelStats {
  double scan = 0;      // distinct labels, padded label-index volume
  double generate = 0;  // map step: keys of the soup
  double weld = 0;      // KEY-REDUCE partition
  double smooth = 0;
  double coarsen = 0;
  Id triangles_before_coarsening = 0;
  Id distinct_labels = 0;   // in the volume, background counted
  Id surfaces = 0;          // labels extracted
  Id soup_corners = 0;      // triangle corners before welding
  // Smoothing moves the fold guard shortened or refused, summed over the
  // points and the iterations (label_fold_guard.cpp).
  Id guard_shortened = 0;
};

// history_key, with options.history: receives every point's key.
SurfaceMesh contour_labels(const ImageGrid& grid, const LabelOptions& options, LabelStats* stats = nullptr,
                           std::vector<std::uint64_t>* history_key = nullptr);

// contour_labels()'s refusals that need no scan of the samples (smoothing
// options, the grid's dims and sample type, the background's magnitude), as
// InputError: what another backend checks before it starts.
void check_labels_input(const ImageGrid& grid, const LabelOptions& options);

// Faces and distinct points per label pair of a mesh with a boundary_labels
// cell field, in increasing (first, second): two KEY-REDUCE partitions (the
// faces by pair, then the corners by (pair, point)). Empty without the field.
std::vector<LabelPairCount> label_pair_counts(const SurfaceMesh& mesh);

}  // namespace keymesh::generate
