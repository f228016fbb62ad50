#pragma once
// A synthetic input for the Neuroglancer multilod writer, standing in for
// the labels meshing: each segment is the surface of an axis-aligned box of
// the sample grid, cut into the pieces each lod-0 chunk gives it.
//   lod k: the box's faces tiled by the cells of the grid of spacing 2^k
//     (clipped to the box), two triangles a cell; a point is keyed by its
//     global sample index, so a point on a face two chunks share has one key
//     and one position in both, and every cell lies in one chunk (chunk
//     shapes are multiples of 2^(lods-1)).
//   Points off the chunk faces are moved by up to 0.3 samples (a function of
//   their key) so quantization has something to round.
// Shared by the gtests (tests/io/neuroglancer_*_test.cpp) and the fixture
// program the Python reader checks (tests/io/neuroglancer_fixture.cpp).
#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <tuple>
#include <vector>

#include "keymesh/io/neuroglancer.hpp"

namespace keymesh::tests::neuroglancer_dataset {

using io::neuroglancer::ChunkPiece;
using io::neuroglancer::MultilodLayout;

struct Box {
  std::uint64_t segment;
  std::array<std::uint32_t, 3> lo, hi;  // sample coordinates, lo < hi
  std::uint32_t max_lod = 31;           // no mesh at coarser lods (a small object coarsened away)
};

inline MultilodLayout layout(bool sharded = false) {
  MultilodLayout l;
  l.chunk_shape = {8, 8, 8};
  l.chunks = {4, 3, 3};
  l.lods = 3;
  l.transform = {2, 0, 0, 10, 0, 3, 0, 20, 0, 0, 4, 30};
  l.sharded = sharded;
  return l;
}

inline std::vector<Box> boxes() {
  // Segment 9 has a mesh at lod 0 only: its lod-1 and lod-2 nodes are listed
  // empty, as parents; segment 7's vanishes at lod 2.
  return {{1, {1, 2, 3}, {30, 20, 21}},      {2, {9, 9, 9}, {14, 14, 14}}, {3, {17, 1, 10}, {23, 7, 22}},
          {9, {3, 12, 3}, {5, 14, 5}, 0}, {7, {25, 17, 17}, {26, 18, 18}, 1}};
}

// `count` small boxes scattered over the grid (for several shards).
inline std::vector<Box> many_boxes(std::uint64_t count) {
  std::vector<Box> out;
  for (std::uint64_t i = 0; i < count; ++i) {
    const std::uint32_t x = static_cast<std::uint32_t>(i % 30), y = static_cast<std::uint32_t>(i / 30 % 22),
                        z = static_cast<std::uint32_t>(i / 660 % 22);
    out.push_back({1000 + 7 * i, {x, y, z}, {x + 1 + static_cast<std::uint32_t>(i % 2), y + 1, z + 2}});
  }
  return out;
}

inline float jitter(std::uint64_t key, int axis) {
  std::uint64_t h = key * 0x9e3779b97f4a7c15ull + static_cast<std::uint64_t>(axis) * 0xbf58476d1ce4e5b9ull;
  h ^= h >> 31;
  h *= 0x94d049bb133111ebull;
  h ^= h >> 29;
  return static_cast<float>(static_cast<double>(h % 1001) / 1000.0 * 0.6 - 0.3);
}

// Cuts of [lo, hi] at the multiples of `step` inside it.
inline std::vector<std::uint32_t> cuts(std::uint32_t lo, std::uint32_t hi, std::uint32_t step) {
  std::vector<std::uint32_t> c{lo};
  for (std::uint32_t v = (lo / step + 1) * step; v < hi; v += step) c.push_back(v);
  c.push_back(hi);
  return c;
}

struct PieceBuilder {
  ChunkPiece piece;
  std::map<std::uint64_t, std::uint32_t> index;
  std::uint32_t point(const MultilodLayout& l, const std::array<std::uint32_t, 3>& p) {
    const std::uint64_t nx = std::uint64_t{l.chunk_shape[0]} * l.chunks[0] + 1, ny = std::uint64_t{l.chunk_shape[1]} * l.chunks[1] + 1;
    const std::uint64_t key = p[0] + nx * (p[1] + ny * p[2]);
    const auto [it, added] = index.emplace(key, static_cast<std::uint32_t>(piece.point_keys.size()));
    if (added) {
      piece.point_keys.push_back(key);
      for (int a = 0; a < 3; ++a)
        piece.points.push_back(static_cast<float>(p[a]) + (p[a] % l.chunk_shape[a] == 0 ? 0.0f : jitter(key, a)));
    }
    return it->second;
  }
};

// The pieces of every box, lod and chunk (pieces in no particular order).
inline std::vector<ChunkPiece> pieces(const MultilodLayout& l, const std::vector<Box>& bs) {
  std::map<std::tuple<std::uint64_t, std::uint32_t, std::array<std::uint32_t, 3>>, PieceBuilder> built;
  for (const Box& b : bs)
    for (std::uint32_t lod = 0; lod < l.lods && lod <= b.max_lod; ++lod)
      for (int axis = 0; axis < 3; ++axis)
        for (std::uint32_t side : {b.lo[axis], b.hi[axis]}) {
          const int u = (axis + 1) % 3, v = (axis + 2) % 3;
          const auto cu = cuts(b.lo[u], b.hi[u], 1u << lod), cv = cuts(b.lo[v], b.hi[v], 1u << lod);
          for (std::size_t i = 0; i + 1 < cu.size(); ++i)
            for (std::size_t j = 0; j + 1 < cv.size(); ++j) {
              std::array<std::array<std::uint32_t, 3>, 4> q;
              for (int c = 0; c < 4; ++c) {
                q[c][axis] = side;
                q[c][u] = c == 1 || c == 2 ? cu[i + 1] : cu[i];
                q[c][v] = c >= 2 ? cv[j + 1] : cv[j];
              }
              std::array<std::uint32_t, 3> chunk;
              for (int a = 0; a < 3; ++a)
                chunk[a] = std::min(std::min({q[0][a], q[2][a]}) / l.chunk_shape[a], l.chunks[a] - 1);
              PieceBuilder& pb = built[{b.segment, lod, chunk}];
              pb.piece.segment = b.segment, pb.piece.lod = lod, pb.piece.chunk = chunk;
              std::uint32_t id[4];
              for (int c = 0; c < 4; ++c) id[c] = pb.point(l, q[c]);
              for (std::uint32_t corner : {id[0], id[1], id[2], id[0], id[2], id[3]}) pb.piece.triangles.push_back(corner);
            }
        }
  std::vector<ChunkPiece> out;
  for (auto& [key, pb] : built) out.push_back(std::move(pb.piece));
  return out;
}

}  // namespace keymesh::tests::neuroglancer_dataset
