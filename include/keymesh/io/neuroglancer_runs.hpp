#pragma once
// What every run of the Neuroglancer multi-resolution output needs around
// the writer (neuroglancer.hpp): the layout of a volume's chunk grid, the
// segment names of a label table, the meshing's pieces as the writer's, the
// one-call write with its chunk store, and the counts a report gives. Shared
// by `keymesh labels --format precomputed` (src/cli/labels_precomputed.cpp)
// and keymesh.labels_precomputed / keymesh.dask.labels_precomputed
// (python/src/labels_precomputed.cpp), so that the CLI, Python and a Dask
// graph write the same bytes (docs/decisions/labels-precomputed-python.md).
//
// The meshing (generate/labels/labels_multilod.hpp) sits beside io, not
// below it: its grid's fields come in as plain values, and its pieces, whose
// fields are ChunkPiece's name for name, through a template.
#include <array>
#include <cstdint>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/io/neuroglancer.hpp"
#include "keymesh/mesh/image_grid.hpp"

namespace keymesh::io::neuroglancer {

// The layout of a chunk grid over `grid` (generate::MultilodGrid's
// chunk_shape, chunks, grid_origin and lods): stored model coordinates are
// sample indices, so the transform is model = origin + spacing * index.
MultilodLayout multilod_layout(const ImageGrid& grid, const std::array<Id, 3>& chunk_shape,
                               const std::array<Id, 3>& chunks, const std::array<double, 3>& grid_origin, int lods,
                               bool sharded);

// The names of a label table (io/label_table.hpp; empty path: none), the
// background's entry left out (it is no segment).
SegmentNames table_segment_names(const std::string& path, std::int64_t background);

// A chunk index as the writer takes it.
std::array<std::uint32_t, 3> chunk_index(const std::array<Id, 3>& chunk);

// The meshing's pieces (generate::MultilodPiece) as the writer's, moved.
template <class Piece>
std::vector<ChunkPiece> to_chunk_pieces(std::vector<Piece>&& pieces) {
  std::vector<ChunkPiece> out(pieces.size());
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    Piece& p = pieces[i];
    out[i].segment = p.segment;
    out[i].lod = p.lod;
    out[i].chunk = p.chunk;
    out[i].point_keys = std::move(p.point_keys);
    out[i].points = std::move(p.points);
    out[i].triangles = std::move(p.triangles);
  }
  return out;
}

// The one-call run's files: the output (write_multilod) and every chunk's
// pieces kept under DIR/chunks/, empty chunks too, so that the store is
// complete for a later --update; all of them appear together or none does.
void write_multilod_and_chunks(const std::string& dir, const MultilodLayout& layout,
                               std::vector<ChunkPiece>&& pieces, const SegmentNames& names);

// What a run made, for its report: pieces, chunks written, the segments they
// belong to, triangles per level of detail (a triangle lies in one chunk, so
// the sum over chunk tasks is the one call's).
struct PieceCounts {
  std::size_t pieces = 0, chunks = 0;
  std::set<std::uint64_t> segments;
  std::vector<std::uint64_t> triangles_per_lod;
  void add(const std::vector<ChunkPiece>& made);
};

}  // namespace keymesh::io::neuroglancer
