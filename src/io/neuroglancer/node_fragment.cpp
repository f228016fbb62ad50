#include "node_fragment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "keymesh/core/types.hpp"
#include "keymesh/keyreduce/groups.hpp"
#include "keymesh/keyreduce/weld.hpp"

namespace keymesh::io::neuroglancer {

namespace {

// Welded points: every pair's group and every group's first pair.
struct Weld {
  keyreduce::Groups<std::uint64_t> groups;
  std::vector<std::uint32_t> first;
};

Weld weld_keys(const std::vector<const ChunkPiece*>& pieces) {
  std::size_t n_keys = 0;
  for (const ChunkPiece* piece : pieces) n_keys += piece->point_keys.size();
  std::vector<std::uint64_t> keys;
  keys.reserve(n_keys);
  for (const ChunkPiece* piece : pieces) keys.insert(keys.end(), piece->point_keys.begin(), piece->point_keys.end());
  const Id n = static_cast<Id>(keys.size());
  Weld weld;
  // Each piece's keys are increasing: their runs are merged, not sorted.
  weld.groups = keyreduce::partition_runs(keys.data(), n, keyreduce::Order::Skip);
  keyreduce::first_pairs(weld.groups, n, weld.first);
  return weld;
}

[[noreturn]] void outside_box(const ChunkPiece& piece, const float* p, const NodeBox& box) {
  std::ostringstream out;
  out << "neuroglancer: internal error: segment " << piece.segment << " lod " << piece.lod << ": point (" << p[0]
      << ", " << p[1] << ", " << p[2] << ") of chunk (" << piece.chunk[0] << ", " << piece.chunk[1] << ", "
      << piece.chunk[2] << ") lies outside its node's box, from (" << box.origin[0] << ", " << box.origin[1] << ", "
      << box.origin[2] << ") by (" << box.size[0] << ", " << box.size[1] << ", " << box.size[2] << ")";
  throw std::logic_error(out.str());
}

// static_cast<int32>(std::clamp(std::round(x), 0.0, top)) for finite x and
// an integer top in [0, 2^31), inline where GCC calls libm's round (3.4
// million calls in a whole-atlas run). The same integer:
// - clamping first changes nothing: round is monotone and leaves the
//   integers 0 and top where they are, so x < 0 gives 0 and x > top gives
//   top either way;
// - for y in [0, top], t = trunc(y) fits an int32 and y - t is exact (for
//   t = 0 it is y; for t >= 1, t <= y < 2t, so Sterbenz's lemma applies),
//   so y - t >= 0.5 decides the half-away-from-zero rounding exactly (unlike
//   y + 0.5, which rounds 0.5 - 2^-54 up to 1).
std::int32_t round_into(double x, double top) {
  const double y = std::clamp(x, 0.0, top);
  const auto t = static_cast<std::int32_t>(y);
  return t + (y - static_cast<double>(t) >= 0.5 ? 1 : 0);
}

// One axis's quantization over the node's box, its bounds computed once per
// fragment.
struct AxisQuantizer {
  double origin, size, max_value, lowest, highest;
  AxisQuantizer(double origin_, double size_, double max_value_) : origin(origin_), size(size_), max_value(max_value_) {
    // Float32 rounding of a point computed on the box's face: a few units in
    // the last place of the largest coordinate involved.
    const double magnitude = std::max(std::abs(origin), std::abs(origin + size));
    const double tolerance = 8 * magnitude * std::numeric_limits<float>::epsilon() + 1e-6 * size;
    lowest = origin - tolerance;
    highest = origin + size + tolerance;
  }
  // One coordinate's quantized value; `inside` false when beyond the tolerance.
  std::int32_t operator()(double p, bool& inside) const {
    if (!(p >= lowest && p <= highest)) inside = false;
    return round_into((p - origin) / size * max_value, max_value);
  }
};

}  // namespace

NodeBox node_box(const MultilodLayout& layout, std::uint32_t lod, const NodePosition& node) {
  NodeBox box;
  for (int a = 0; a < 3; ++a) {
    box.size[a] = std::ldexp(static_cast<double>(layout.chunk_shape[a]), static_cast<int>(lod));
    box.origin[a] = static_cast<double>(layout.grid_origin[a]) + static_cast<double>(node[a]) * box.size[a];
  }
  return box;
}

QuantizedMesh node_fragment(const std::vector<const ChunkPiece*>& pieces, const NodeBox& box, int quantization_bits) {
  const Weld weld = weld_keys(pieces);
  const double max_value = std::ldexp(1.0, quantization_bits) - 1;
  QuantizedMesh mesh;
  mesh.positions.resize(3 * weld.first.size());
  // Pair numbers where each piece's points begin (the pieces' points concatenated).
  std::vector<std::size_t> piece_begin{0};
  for (const ChunkPiece* piece : pieces) piece_begin.push_back(piece_begin.back() + piece->point_keys.size());
  const AxisQuantizer quantize[3] = {{box.origin[0], box.size[0], max_value},
                                     {box.origin[1], box.size[1], max_value},
                                     {box.origin[2], box.size[2], max_value}};
  for (std::size_t g = 0; g < weld.first.size(); ++g) {
    // A group's coordinates are its first pair's (the pairs of a key agree).
    const std::size_t pair = weld.first[g];
    const std::size_t k = static_cast<std::size_t>(std::upper_bound(piece_begin.begin(), piece_begin.end(), pair) - piece_begin.begin()) - 1;
    const ChunkPiece& piece = *pieces[k];
    const float* p = &piece.points[3 * (pair - piece_begin[k])];
    bool inside = true;
    for (int a = 0; a < 3; ++a) mesh.positions[3 * g + a] = quantize[a](p[a], inside);
    if (!inside) outside_box(piece, p, box);
  }
  std::size_t corners = 0;
  for (const ChunkPiece* piece : pieces) corners += piece->triangles.size();
  mesh.triangles.reserve(corners);
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const ChunkPiece& piece = *pieces[k];
    for (std::size_t t = 0; t < piece.triangles.size(); t += 3) {
      std::uint32_t corner[3];
      for (int c = 0; c < 3; ++c) corner[c] = weld.groups.index_map[piece_begin[k] + piece.triangles[t + c]];
      if (corner[0] == corner[1] || corner[1] == corner[2] || corner[0] == corner[2])
        throw std::logic_error("neuroglancer: internal error: segment " + std::to_string(piece.segment) + " lod " +
                               std::to_string(piece.lod) + ": a triangle has two corners of one point key");
      mesh.triangles.insert(mesh.triangles.end(), corner, corner + 3);
    }
  }
  return mesh;
}

}  // namespace keymesh::io::neuroglancer
