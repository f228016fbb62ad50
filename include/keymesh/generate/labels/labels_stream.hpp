#pragma once
// Label maps streamed in slabs (`keymesh labels --memory-limit`) and split
// over the ranks of `mpirun -np P keymesh labels` (issue 18).
//
// What is streamed is the input volume: it is read in slabs of z-planes, each
// slab's planes mapped to label indices and turned into that slab's pieces of
// the surfaces, with global keys (surface nets: the cell, or the label box's
// cell and loop; discrete MC: the edge of the padded grid). The pieces are
// then merged by key (one KEY-REDUCE: a point two slabs share has one key and
// is computed from the same samples by both) and the welded mesh is smoothed
// and written as a whole: smoothing needs every point's neighbours, across
// slab borders, and the output is one file anyway. So memory holds a slab of
// samples plus the output mesh (and its soup, before the merge).
//
// The output is byte-identical to contour_labels on the whole volume in
// memory, for both methods, --per-label and any smoothing: the same keys give
// the same point order, the slabs give the faces in grid order, and each
// label's faces (per label, and discrete MC's network, whose faces run label
// by label) are gathered across slabs before the next label's.
//
// The planes are read three times: the distinct labels (to number them),
// their voxel counts and bounding boxes (the per-label key spaces), then the
// surfaces. A slab of R rows holds R + 2 planes (one either side: a cell or
// cube of the slab's last row reads the plane above, and junction flags look
// one plane further) of samples and of 16-bit label indices.
#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

#include "keymesh/mesh/plane_source.hpp"
#include "keymesh/generate/labels/labels.hpp"

namespace keymesh::generate {

struct LabelStreamStats {
  Id slabs = 0;
  Id rows_per_slab = 0;         // padded planes of faces per slab
  std::size_t slab_bytes = 0;   // samples and label indices held at once
  double read = 0;              // reading planes, over the three passes
  double merge = 0;             // merging the slabs' pieces by key
  Id halo_rows = 0;             // generate_with_halo: rows made for the neighbours' sake
};

// A rank's share of the surfaces when every rank writes its own piece
// (`mpirun -np P keymesh labels -o OUT.pvtp`): the surfaces of its rows and
// of halo rows either side, merged, smoothed and coarsened there as one
// process does it. A point's smoothed position after n Jacobi steps depends
// only on the points within n cells of it, and every sum runs in key order
// (global), so what lies deeper than the steps and the coarsening's reach
// inside the halo is bit for bit the one process's.
struct LabelPiece {
  SurfaceMesh mesh;                     // finished: smoothed, coarsened, with the label fields
  std::vector<std::uint8_t> ghost_face; // per triangle: 1 when a halo row made it (another rank's)
  // Per point: a key ascending in the output's point order (segment << 47 |
  // key in the segment) and the padded row that owns it; within a segment
  // the row never decreases. Points of the output are numbered segment
  // after segment, key order within each.
  std::vector<std::uint64_t> order_key;
  std::vector<Id> row;
  int segments = 1;
  std::vector<std::uint64_t> history_key;  // per point, with LabelOptions::history
};

// The passes of a streamed label map, for one process or one rank. A
// process handles padded rows [first_row, end_row) of the nz + 2 (the
// volume padded with one plane of background either side); between the
// passes, ranks exchange what the set_ calls take (every rank's distinct
// labels; every rank's counts; every rank's pieces, on one rank).
class LabelSlabs {
 public:
  // Throws InputError (float volume, bad background) and LimitError (the
  // memory limit holds fewer than three planes of samples and indices).
  LabelSlabs(PlaneSource& source, const LabelOptions& options, std::size_t memory_limit,
             std::pair<Id, Id> rows);
  LabelSlabs(PlaneSource& source, const LabelOptions& options, std::size_t memory_limit);  // every row
  ~LabelSlabs();
  LabelSlabs(const LabelSlabs&) = delete;
  LabelSlabs& operator=(const LabelSlabs&) = delete;

  // Pass 1: the sorted distinct labels of this process's planes.
  std::vector<std::int64_t> distinct_labels();
  // Every process's distinct labels, in any order: numbers the labels and
  // applies the selection (InputError as contour_labels).
  void set_labels(const std::vector<std::vector<std::int64_t>>& all);
  // Pass 2: voxel counts and boxes of this process's planes, as bytes.
  std::vector<std::byte> count_labels();
  void set_counts(const std::vector<std::vector<std::byte>>& all);
  // Pass 3: this process's pieces of the surfaces (kept).
  void generate();
  // Pass 3 for a rank writing its own piece: its rows and `halo` rows either
  // side (those that exist), the halo's triangles marked as ghosts; then
  // finish_piece() instead of finish().
  void generate_with_halo(Id halo);
  LabelPiece finish_piece();
  // The halo rows a piece needs for these options: a point moves by its
  // neighbours' positions once per smoothing step (two per Taubin
  // iteration), a cell a step, and coarsening reaches a block and its
  // faces' groups further; the rest is margin.
  static Id halo_rows(const LabelOptions& options);
  // This process's pieces as bytes, to send; and another process's pieces
  // received, appended in the order the processes' rows run.
  std::vector<std::byte> pieces_bytes() const;
  void add_pieces(const std::vector<std::byte>& bytes);
  // The pieces held merged by key, smoothed, with the label fields;
  // history_key (LabelOptions::history) receives every point's key.
  SurfaceMesh finish(std::vector<std::uint64_t>* history_key = nullptr);

  static Id total_rows(const ImageGrid& header) { return header.dims[2] + 2; }
  const LabelStats& stats() const;
  const LabelStreamStats& stream_stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One process, every row: the passes above in order. memory_limit: bytes of
// samples and label indices held at once (at least three planes of each);
// the output mesh comes on top.
SurfaceMesh contour_labels_streamed(PlaneSource& source, const LabelOptions& options, std::size_t memory_limit,
                                    LabelStats* stats = nullptr, LabelStreamStats* stream_stats = nullptr,
                                    std::vector<std::uint64_t>* history_key = nullptr);

}  // namespace keymesh::generate
