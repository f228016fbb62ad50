#pragma once
// The label map as the label generators read it (internal to src/generate):
// each sample replaced by the index of its label among the volume's sorted
// distinct labels, padded with one layer of background all round so that no
// generator has a border case and every region's surface closes.
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "keymesh/generate/labels/labels.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/generate/labels/label_kernels.hpp"

namespace keymesh::generate::detail {

using LabelIndex = std::uint16_t;  // < kMaxDistinctLabels

struct LabelVolume {
  std::array<Id, 3> dims{};   // padded: grid dims + 2
  Id nxy = 0, n = 0;          // padded sizes
  std::array<double, 3> origin{}, spacing{};  // of the unpadded grid
  // The label indices of padded planes [first_plane, first_plane + planes),
  // x fastest: every plane in memory, or a window of them when the volume is
  // streamed in slabs (labels_stream.cpp). Addressed by global point ids.
  std::vector<LabelIndex> index;
  Id first_plane = 0;
  bool window = false;  // generators then also keep each point's key (LabelSurface::keys)
  bool keep_keys = false;  // the same in memory (multilod chunks need every point's key)
  // --coarsen: generators give every point its coarse key (LabelSurface::coarse).
  bool coarse_keys = false;
  bool per_label = false;

  // The coarse key of a point (coarsening, label_coarsen.cpp): the 2x2x2
  // block of padded cells holding cell (i, j, k) (surface nets), or a padded
  // point's id (discrete MC: a midpoint's nearest grid point, the edge's
  // lower end on a tie, which a midpoint always is). Per label, the label
  // index goes above bit 44 so that labels' surfaces never merge.
  std::uint64_t block_key(Id i, Id j, Id k) const {
    const Id bx = dims[0] / 2 + 1, by = dims[1] / 2 + 1;
    return static_cast<std::uint64_t>(i / 2 + (j / 2) * bx + (k / 2) * bx * by);
  }
  std::uint64_t part_key(std::uint64_t key, LabelIndex label) const {
    return per_label ? (std::uint64_t{label} + 1) << 44 | key : key;
  }
  std::vector<std::int64_t> values;      // label value of every index, increasing
  LabelIndex background = 0;             // index of the background value
  std::vector<LabelIndex> stored;        // per value index: what the grid stores (background when not selected)
  Id distinct_in_grid = 0;               // distinct values the grid holds
  // Selected labels (indices, increasing) with their voxel counts and the
  // bounding box of their voxels in padded coordinates, [lo, hi] inclusive.
  std::vector<LabelIndex> selected;
  std::vector<Id> voxels;
  std::vector<std::array<Id, 6>> box;

  Id at(Id i, Id j, Id k) const { return i + j * dims[0] + k * nxy; }
  // Label index of padded point p (a global id; its plane must be held).
  LabelIndex label(Id p) const { return index[static_cast<std::size_t>(p - first_plane * nxy)]; }
  const LabelIndex* row(Id p) const { return index.data() + (p - first_plane * nxy); }
  // Position of padded grid point (i, j, k) along axis a.
  double coord(int a, double i) const { return origin[a] + spacing[a] * (i - 1.0); }
};

// The volume's placement of points (label_kernels.hpp: what the device path
// reads instead of the volume).
inline label_kernels::Placement placement(const LabelVolume& v) {
  return {{v.origin[0], v.origin[1], v.origin[2]},
          {v.spacing[0], v.spacing[1], v.spacing[2]},
          {v.dims[0], v.dims[1], v.dims[2]}};
}

// Voxel counts and bounding boxes (padded coordinates, [lo, hi]) per label
// index, summed over the planes mapped so far.
struct LabelCounts {
  std::vector<Id> voxels;
  std::vector<std::array<Id, 6>> box;
  void reset(Id labels);
  void merge(const LabelCounts& other);
};

// Where the labels go, which bounds them: the float32 cell fields
// boundary_labels and label of a mesh (|label| <= kMaxLabelMagnitude, which
// float32 holds exactly; coarsening and history read labels back from
// them), or the label table only (Neuroglancer segment ids: any int64, so
// uint32 and int64 volumes whole and uint64 up to 2^63 - 1).
enum class LabelRange { Float32Fields, Int64Table };

// Throws InputError naming grid.name-less context ("labels: ...") for float
// samples, labels past the range (and uint64 labels past 2^63 - 1), too
// many distinct labels, a selected label the volume does not hold or a
// selected background. The whole volume in memory: the steps below in one go.
LabelVolume scan_labels(const ImageGrid& grid, const LabelOptions& options,
                        LabelRange range = LabelRange::Float32Fields);

// The steps of scan_labels, for volumes streamed in slabs (labels_stream.cpp):
// the header's checks; the sorted distinct values of some planes (merged
// across slabs, capped past the limit); the table of values, background and
// selection (no planes yet); a window of padded planes; the file planes
// [first, first + planes.dims[2]) mapped into the window (which must hold
// padded planes first + 1 ...), counted when `counts` is given; and the
// selected labels' counts and boxes once every plane was counted.
void check_label_grid(const ImageGrid& header, const LabelOptions& options,
                      LabelRange range = LabelRange::Float32Fields);
std::vector<std::int64_t> distinct_labels(const ImageGrid& samples);
void merge_distinct(std::vector<std::int64_t>& into, const std::vector<std::int64_t>& more);
LabelVolume label_table(const ImageGrid& header, std::vector<std::int64_t> values, const LabelOptions& options,
                        LabelRange range = LabelRange::Float32Fields);
void allocate_window(LabelVolume& vol, Id first_plane, Id planes);
void map_planes(LabelVolume& vol, const ImageGrid& planes, Id first, LabelCounts* counts);
void set_boxes(LabelVolume& vol, const LabelCounts& counts);

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
  // Per point, its key (the cell, edge or face it stands for, in the key
  // space of its surface), kept by generators running on a window of a
  // streamed volume: the slabs' pieces of a surface are merged by key.
  std::vector<std::uint64_t> keys;
  // Per point, its coarse key (LabelVolume::coarse_keys).
  std::vector<std::uint64_t> coarse;
  // Per triangle, in a rank's surface grown by halo rows (LabelSlabs::
  // generate_with_halo): 1 where a halo row made it (another rank's
  // triangle). Empty otherwise. Kept through the merge and coarsening.
  std::vector<std::uint8_t> ghost_face;
  // Per point, with LabelOptions::history: its history_key (label_history.cpp),
  // set by finish_label_mesh from `keys`.
  std::vector<std::uint64_t> history_key;
};

// Appends the parts (their own points each) to `out`, in order.
void append_surfaces(std::vector<LabelSurface>& parts, LabelSurface& out);

LabelSurface surface_nets(const LabelVolume& volume, bool per_label, LabelStats& stats);
LabelSurface discrete_marching_cubes(const LabelVolume& volume, bool per_label, LabelStats& stats);

// The same generators on a window of a streamed volume: the faces of padded
// edge rows (surface nets) or cube rows (discrete MC) [rows.first,
// rows.second) only, the window holding planes rows.first - 1 to
// rows.second + 1 (those that exist). Returns the pieces of the output's
// parts, each welded within the slab, with point keys: surface nets one part
// (the network) or one per selected label (per_label); discrete MC one per
// selected label always (the network's triangles run label by label).
std::vector<LabelSurface> surface_nets_rows(const LabelVolume& window, bool per_label, std::pair<Id, Id> rows,
                                            LabelStats& stats);
std::vector<LabelSurface> discrete_marching_cubes_rows(const LabelVolume& window, std::pair<Id, Id> rows,
                                                       LabelStats& stats);

// Per point of a finished surface of a streamed volume (its keys: fine, or
// coarse after coarsening; `part_points`: the points of each part, per
// label, before coarsening), the padded row it lies in and a key that
// ascends in the output's point order: segment << 47 | key in the segment,
// the row never decreasing within a segment. Returns the segments.
int point_rows(const LabelVolume& vol, const LabelOptions& options, const std::vector<std::uint64_t>& keys,
               const std::vector<Id>& part_points, std::vector<std::uint64_t>& order_key, std::vector<Id>& row);

// Throws InputError for smoothing options out of range.
void check_label_options(const LabelOptions& options);

// Smoothing (options), then the cell field boundary_labels from the pairs,
// before the generator's own fields: the mesh contour_labels returns.
SurfaceMesh finish_label_mesh(LabelSurface& surface, const LabelVolume& volume, const LabelOptions& options,
                              LabelStats& stats);

// --history (label_history.cpp): the surface's history_key from its point
// keys (kept: LabelVolume::keep_keys or window) and the point field history_t.
void add_label_history(LabelSurface& surface, const LabelVolume& volume, const LabelOptions& options);

// --coarsen (label_coarsen.cpp): merges the points by coarse key, averaging
// their positions; drops faces that collapse and cancels faces of one label
// pair on the same three points facing opposite ways. Keeps each face's pair
// and cell fields. A surface with point keys is left with the coarse keys of
// the points kept (increasing).
void coarsen_label_surface(LabelSurface& surface, LabelStats& stats);

// Smooths the surface's points in place (label_smoothing.cpp): Jacobi
// iterations over neighbour lists built by KEY-REDUCE. Returns the moves
// the fold guard shortened or refused (LabelStats::guard_shortened).
Id smooth_label_surface(LabelSurface& surface, const LabelVolume& volume, LabelMethod method, int iterations,
                        double relaxation);

// How many cells away a smoothed point's position may depend on (halo rows,
// chunk halos): an iteration's steps plus one (the fold guard reads the
// neighbours' moves).
Id smoothing_reach(const LabelOptions& options);

}  // namespace keymesh::generate::detail
