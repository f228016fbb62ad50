// The steps around the multilod writer that the CLI's and Python's runs
// share (keymesh/io/neuroglancer_runs.hpp).
#include "keymesh/io/label_table.hpp"
#include "keymesh/io/neuroglancer_runs.hpp"

namespace keymesh::io::neuroglancer {

MultilodLayout multilod_layout(const ImageGrid& grid, const std::array<Id, 3>& chunk_shape,
                               const std::array<Id, 3>& chunks, const std::array<double, 3>& grid_origin, int lods,
                               bool sharded) {
  MultilodLayout layout;
  for (int a = 0; a < 3; ++a) {
    layout.chunk_shape[a] = static_cast<std::uint32_t>(chunk_shape[a]);
    layout.chunks[a] = static_cast<std::uint32_t>(chunks[a]);
    layout.grid_origin[a] = static_cast<float>(grid_origin[a]);
    // Stored model coordinates are sample indices: model = origin + spacing * index.
    layout.transform[4 * a + a] = grid.spacing[a];
    layout.transform[4 * a + 3] = grid.origin[a];
  }
  layout.lods = static_cast<std::uint32_t>(lods);
  layout.sharded = sharded;
  return layout;
}

SegmentNames table_segment_names(const std::string& path, std::int64_t background) {
  if (path.empty()) return {};
  SegmentNames names = read_label_table(path);
  if (background >= 0) names.erase(static_cast<std::uint64_t>(background));
  return names;
}

std::array<std::uint32_t, 3> chunk_index(const std::array<Id, 3>& c) {
  return {static_cast<std::uint32_t>(c[0]), static_cast<std::uint32_t>(c[1]), static_cast<std::uint32_t>(c[2])};
}

void PieceCounts::add(const std::vector<ChunkPiece>& made) {
  pieces += made.size();
  for (const auto& p : made) {
    segments.insert(p.segment);
    if (triangles_per_lod.size() <= p.lod) triangles_per_lod.resize(p.lod + 1, 0);
    triangles_per_lod[p.lod] += p.triangles.size() / 3;
  }
}

}  // namespace keymesh::io::neuroglancer
