#pragma once
// Neuroglancer's precomputed multi-resolution mesh format
// ("neuroglancer_multilod_draco": google/neuroglancer,
// src/datasource/precomputed/meshes.md and sharded.md), written from the
// pieces that each lod-0 chunk of a label volume contributes to each
// segment's mesh at each level of detail.
//
// Coordinates: "stored model" space is grid index space (sample i at i);
// `transform` maps it to the volume's physical space (spacing, origin).
// The octree's lod-0 node (i, j, k) is the box
//   grid_origin + [i, j, k] * chunk_shape  ...  + chunk_shape
// and a lod-k node covers 2^k lod-0 chunks along each axis.
//
// Chunk pieces carry global point keys: a point on the face two chunks
// share has the same key (and the same coordinates) in both, so a lod-k
// fragment is the pieces of its lod-0 chunks welded by key (one
// KEY-REDUCE), and no triangle crosses a child node's border (the format's
// 2x2x2 rule for lod > 0).
//
// Contract between the meshing (generate/labels) and this writer (io);
// the CLI is `keymesh labels IN -o DIR --format precomputed`.
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace keymesh::io::neuroglancer {

struct MultilodLayout {
  std::array<std::uint32_t, 3> chunk_shape{32, 32, 32};  // lod-0 node, in samples
  std::array<std::uint32_t, 3> chunks{1, 1, 1};          // lod-0 nodes per axis covering the grid
  std::array<float, 3> grid_origin{0, 0, 0};             // stored model coordinates of node (0,0,0)
  std::uint32_t lods = 1;
  // Row-major 3x4 matrix from stored model to model (physical) coordinates.
  std::array<double, 12> transform{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  int vertex_quantization_bits = 16;  // 10 or 16
  bool sharded = false;
};

// One lod-0 chunk's share of one segment's mesh at one level of detail.
struct ChunkPiece {
  std::uint64_t segment = 0;
  std::uint32_t lod = 0;
  std::array<std::uint32_t, 3> chunk{0, 0, 0};  // lod-0 chunk index
  std::vector<std::uint64_t> point_keys;       // one per point, global (equal on shared faces)
  std::vector<float> points;                   // x,y,z per point, stored model coordinates, inside the chunk's box
  std::vector<std::uint32_t> triangles;        // 3 per triangle, indices into points
};

// Segment names for the info's segment_properties (empty: none written).
using SegmentNames = std::map<std::uint64_t, std::string>;

// The whole output from pieces in memory (the one-call run): DIR/info, and
// per segment its manifest and fragment data (`<id>.index` and `<id>`, or
// the sharded layout), fragments Draco-encoded with integer positions
// quantized to vertex_quantization_bits over the node's box.
// (src/io/neuroglancer/; docs/decisions/neuroglancer-multilod.md.)
//  - Bytes depend only on the set of pieces: not on their order, nor the thread count.
//  - Pieces without triangles are ignored; a segment with none has no files.
//  - Every file of one call appears together or none does (OutputTransaction);
//    earlier outputs this write does not hold (files named like a segment's
//    or a shard's, segment_properties/info) are removed with it.
//  - InputError for a bad layout or piece (lod or chunk outside the layout,
//    array sizes that disagree, a corner past the piece's points, one
//    segment/lod/chunk given twice); std::logic_error (an internal error)
//    for a point outside its node's box beyond float rounding.
void write_multilod(const std::string& dir, const MultilodLayout& layout, const std::vector<ChunkPiece>& pieces,
                    const SegmentNames& names = {});

// Chunk tasks (`--chunk I J K`): one chunk's pieces kept under DIR/chunks/
// (DIR/chunks/I_J_K.pieces, checked by a CRC) until the final step assembles
// them; a chunk's pieces replace any earlier. Every chunk's task must write
// its file, an empty list included. The first task records the layout in
// DIR/chunks/layout.json; a later task or final step with another layout is
// refused (InputError naming the field). Tasks may run concurrently.
void write_chunk_pieces(const std::string& dir, const MultilodLayout& layout, const std::array<std::uint32_t, 3>& chunk,
                        const std::vector<ChunkPiece>& pieces);
std::vector<ChunkPiece> read_chunk_pieces(const std::string& dir, const std::array<std::uint32_t, 3>& chunk);

// The segments (increasing, once each) of a chunk's kept pieces, read without
// their points; empty when the chunk's task has not run. Before `--update`
// re-runs a chunk: these and its new pieces' segments are the `segments`
// assemble_multilod must rewrite.
std::vector<std::uint64_t> kept_segments(const std::string& dir, const std::array<std::uint32_t, 3>& chunk);

// The final step: the output from every chunk's kept pieces, equal byte for
// byte to write_multilod over the same pieces. With `segments` non-empty,
// only those segments' manifests and data (or the shards holding them,
// rebuilt from every kept piece of the segments they hold) are rewritten
// (`--update`), a segment or shard left without a mesh removed; `segments`
// must then hold every segment whose pieces changed (the old and the new
// pieces' segments of the re-run chunks). When the existing DIR/info differs
// from this run's (sharding parameters, quantization, names), the whole
// output is rewritten instead.
// `batch_bytes` (0: no bound) bounds the pieces held at once: the segments
// (whole shards when sharded) are written in batches whose pieces take
// about that much memory, every chunk file read once per batch; a segment
// larger than the bound is a batch of its own. The bytes written do not
// depend on it. Returns the number of batches (1 without a bound).
std::size_t assemble_multilod(const std::string& dir, const MultilodLayout& layout,
                              const std::vector<std::uint64_t>& segments, const SegmentNames& names = {},
                              std::uint64_t batch_bytes = 0);

}  // namespace keymesh::io::neuroglancer
