#include "segment_mesh.hpp"

#include <algorithm>
#include <limits>

#include "keymesh/core/error.hpp"
#include "coincident_points.hpp"
#include "collinear_triangles.hpp"
#include "face_points.hpp"
#include "manifest.hpp"
#include "node_fragment.hpp"
#include "octree_nodes.hpp"

namespace keymesh::io::neuroglancer {

namespace {

NodePosition node_of(const ChunkPiece& piece) {
  return {piece.chunk[0] >> piece.lod, piece.chunk[1] >> piece.lod, piece.chunk[2] >> piece.lod};
}

// Pieces by lod, then node in Z-curve order, then chunk: a node's pieces are
// one run, and the runs come in manifest order.
bool piece_less(const ChunkPiece* a, const ChunkPiece* b) {
  if (a->lod != b->lod) return a->lod < b->lod;
  const NodePosition na = node_of(*a), nb = node_of(*b);
  if (na != nb) return zorder_less(na, nb);
  return a->chunk < b->chunk;
}

std::uint32_t fragment_size(std::size_t bytes, std::uint64_t segment) {
  if (bytes > std::numeric_limits<std::uint32_t>::max())
    throw LimitError("neuroglancer: segment " + std::to_string(segment) +
                     ": a fragment passes 4 GiB, the manifest's 32-bit size (use a smaller --chunk-shape)");
  return static_cast<std::uint32_t>(bytes);
}

}  // namespace

SegmentFiles encode_segment(const MultilodLayout& layout, std::uint64_t segment, std::vector<const ChunkPiece*> pieces) {
  SegmentFiles files;
  files.segment = segment;
  std::erase_if(pieces, [](const ChunkPiece* p) { return p->triangles.empty(); });
  if (pieces.empty()) return files;
  std::sort(pieces.begin(), pieces.end(), piece_less);
  std::vector<std::vector<NodePosition>> nonempty(layout.lods);
  for (const ChunkPiece* p : pieces) nonempty[p->lod].push_back(node_of(*p));
  const std::vector<std::vector<NodePosition>> listed = listed_nodes(std::move(nonempty));
  std::vector<LodFragments> lods(layout.lods);
  auto next = pieces.begin();
  std::vector<const ChunkPiece*> node_pieces;
  for (std::uint32_t lod = 0; lod < layout.lods; ++lod)
    for (const NodePosition& node : listed[lod]) {
      node_pieces.clear();
      for (; next != pieces.end() && (*next)->lod == lod && node_of(**next) == node; ++next) node_pieces.push_back(*next);
      std::string fragment;
      if (!node_pieces.empty()) {
        QuantizedMesh mesh = node_fragment(node_pieces, node_box(layout, lod, node), layout.vertex_quantization_bits);
        settle_face_points(mesh, layout.vertex_quantization_bits, merge_coincident_points(mesh));
        flip_collinear_triangles(mesh);
        fragment = encode_draco_fragment(mesh);
      }
      lods[lod].positions.push_back(node);
      lods[lod].sizes.push_back(fragment_size(fragment.size(), segment));
      files.data += fragment;
    }
  files.manifest = manifest_bytes(layout, lods);
  return files;
}

}  // namespace keymesh::io::neuroglancer
