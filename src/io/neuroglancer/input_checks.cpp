#include "input_checks.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

#include "keymesh/core/error.hpp"

namespace keymesh::io::neuroglancer {

namespace {

std::string where(const ChunkPiece& p) {
  std::ostringstream out;
  out << "neuroglancer: the piece of segment " << p.segment << " at lod " << p.lod << " in chunk (" << p.chunk[0] << ", "
      << p.chunk[1] << ", " << p.chunk[2] << ")";
  return out.str();
}

}  // namespace

void check_layout(const MultilodLayout& layout) {
  const auto fail = [](const std::string& why) { throw InputError("neuroglancer: " + why); };
  if (layout.vertex_quantization_bits != 10 && layout.vertex_quantization_bits != 16)
    fail("vertex_quantization_bits is " + std::to_string(layout.vertex_quantization_bits) + " (the format allows 10 or 16)");
  if (layout.lods < 1 || layout.lods > 32) fail("lods is " + std::to_string(layout.lods) + " (expected 1 to 32)");
  for (int a = 0; a < 3; ++a) {
    if (layout.chunk_shape[a] == 0) fail("a chunk_shape of 0 samples");
    if (layout.chunks[a] == 0) fail("a grid of 0 chunks along an axis");
    if (!std::isfinite(layout.grid_origin[a])) fail("grid_origin is not finite");
  }
  for (double t : layout.transform)
    if (!std::isfinite(t)) fail("the transform holds a number that is not finite");
}

void check_piece(const MultilodLayout& layout, const ChunkPiece& piece) {
  const auto fail = [&](const std::string& why) { throw InputError(where(piece) + ": " + why); };
  if (piece.lod >= layout.lods) fail("lod past the layout's " + std::to_string(layout.lods) + " levels");
  for (int a = 0; a < 3; ++a)
    if (piece.chunk[a] >= layout.chunks[a]) fail("chunk outside the layout's grid of chunks");
  if (piece.points.size() != 3 * piece.point_keys.size())
    fail(std::to_string(piece.points.size()) + " coordinates for " + std::to_string(piece.point_keys.size()) + " point keys");
  if (piece.triangles.size() % 3 != 0) fail("a triangle list whose length is not a multiple of 3");
  if (piece.point_keys.size() > 0xffffffffu) fail("more than 2^32 - 1 points");
  for (std::uint32_t corner : piece.triangles)
    if (corner >= piece.point_keys.size())
      fail("a triangle names point " + std::to_string(corner) + " of " + std::to_string(piece.point_keys.size()));
}

std::vector<std::pair<std::uint64_t, std::vector<const ChunkPiece*>>> pieces_by_segment(const std::vector<ChunkPiece>& pieces) {
  std::vector<const ChunkPiece*> order;
  order.reserve(pieces.size());
  for (const ChunkPiece& p : pieces) order.push_back(&p);
  const auto key = [](const ChunkPiece* p) { return std::tie(p->segment, p->lod, p->chunk); };
  std::stable_sort(order.begin(), order.end(), [&](const ChunkPiece* a, const ChunkPiece* b) { return key(a) < key(b); });
  std::vector<std::pair<std::uint64_t, std::vector<const ChunkPiece*>>> groups;
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i > 0 && key(order[i - 1]) == key(order[i])) throw InputError(where(*order[i]) + " is given twice");
    if (groups.empty() || groups.back().first != order[i]->segment) groups.emplace_back(order[i]->segment, std::vector<const ChunkPiece*>{});
    groups.back().second.push_back(order[i]);
  }
  return groups;
}

}  // namespace keymesh::io::neuroglancer
