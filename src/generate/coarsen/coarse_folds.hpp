#pragma once
// Folds of the coarsened contour, found where they can be: remove_folds'
// rule (generate/coarsen.hpp: of every set of triangles over the same three
// points, none is kept when their orientations cancel, else the first of the
// winning orientation) applied inside the contour's triangle pass, without
// comparing the mesh's triangles with one another.
//
// A coarse triangle's points are corners of its voxel (each crossing moved
// to the nearer end of its edge). Three corners of a voxel that do not lie on
// one face of it belong to no other voxel: such a triangle can only equal
// triangles of its own voxel, and is decided there. Three corners on a face
// are shared with the voxel across that face only: such a "face triangle"
// can equal triangles of either voxel on that face, and is decided once both
// voxels' face triangles are known, by the grid row that owns the face.
// Corners are numbered x | y << 1 | z << 2 (the cube case's bit order).
#include <algorithm>
#include <bit>
#include <cstdint>
#include <vector>

#include "keymesh/core/types.hpp"

namespace keymesh::generate {

// Orientation of a triangle over three distinct labels: true when it is a
// rotation of the labels in increasing order. Two triangles over the same
// three points compare alike under any labelling of the points.
inline bool increasing_rotation(unsigned a, unsigned b, unsigned c) {
  return (a < b) + (b < c) + (c < a) == 2;
}

// What the fold rule needs of one coarse triangle, from its three corners.
struct CornerTriangle {
  bool on_face = false;
  bool positive = false;   // orientation (in the face's corner labels for a face triangle)
  std::uint8_t points = 0; // not on a face: its corners as a set of bits
  std::uint8_t code = 0;   // on a face: axis | side << 2 | the face's missing corner << 3 | positive << 5

  CornerTriangle() = default;
  CornerTriangle(unsigned a, unsigned b, unsigned c) {
    const unsigned ones = a & b & c, zeros = ~(a | b | c) & 7u, fixed = ones | zeros;
    if (!fixed) {
      positive = increasing_rotation(a, b, c);
      points = static_cast<std::uint8_t>((1u << a) | (1u << b) | (1u << c));
      return;
    }
    // Three distinct corners share at most one coordinate: one face.
    on_face = true;
    const unsigned axis = static_cast<unsigned>(std::countr_zero(fixed)), side = (ones >> axis) & 1u;
    // The corner within the face: its two other coordinate bits, the same
    // labels seen from the voxels on both sides.
    auto in_face = [axis](unsigned q) { return (q & ((1u << axis) - 1u)) | ((q >> (axis + 1)) << axis); };
    const unsigned fa = in_face(a), fb = in_face(b), fc = in_face(c);
    positive = increasing_rotation(fa, fb, fc);
    code = static_cast<std::uint8_t>(axis | side << 2 | (6u - fa - fb - fc) << 3 | unsigned{positive} << 5);
  }
};

// Applies the rule to a set of equal triangles, in mesh order: calls
// drop(m) for every member m but the one kept. `positive(m)` is member m's
// orientation.
template <class Positive, class Drop>
void resolve_equal_triangles(int n, Positive&& positive, Drop&& drop) {
  int net = 0;
  for (int m = 0; m < n; ++m) net += positive(m) ? 1 : -1;
  bool kept = false;
  for (int m = 0; m < n; ++m) {
    const bool winner = net != 0 && !kept && positive(m) == (net > 0);
    kept = kept || winner;
    if (!winner) drop(m);
  }
}

// One voxel's coarse triangles (at most five, written at `tri`, with their
// corner facts): the triangles not on a face that share their points with
// another of the voxel are decided here, and the voxel's triangles packed.
// Returns the number kept.
inline int fold_within_voxel(std::uint32_t* tri, const CornerTriangle* facts, int n, int* kept_index) {
  bool drop[5] = {false, false, false, false, false}, decided[5] = {false, false, false, false, false};
  bool any = false;
  for (int a = 0; a < n; ++a) {
    if (facts[a].on_face || decided[a]) continue;
    int members[5], m = 0;
    for (int b = a; b < n; ++b)
      if (!facts[b].on_face && facts[b].points == facts[a].points) members[m++] = b, decided[b] = true;
    if (m == 1) continue;
    any = true;
    resolve_equal_triangles(m, [&](int x) { return facts[members[x]].positive; },
                            [&](int x) { drop[members[x]] = true; });
  }
  if (!any) {
    for (int a = 0; a < n; ++a) kept_index[a] = a;
    return n;
  }
  int out = 0;
  for (int a = 0; a < n; ++a) {
    if (drop[a]) continue;
    for (int c = 0; c < 3; ++c) tri[3 * out + c] = tri[3 * a + c];
    kept_index[out++] = a;
  }
  return out;
}

// A face triangle, recorded for the row that decides its face.
struct FaceTriangle {
  std::uint32_t tri;    // index among its voxel row's triangles
  std::uint32_t i;      // its voxel along the row
  std::uint8_t code;    // CornerTriangle::code
  std::uint8_t folded;  // 1 once fold_across_faces dropped it (a member of its own, so
                        // that marking it races with no thread reading the others)
};

// A face triangle as fold_across_faces sorts it.
struct FoldEntry {
  std::uint64_t key;      // the face and its three points
  std::uint32_t row, tri; // mesh order: row 0 (this one) before 1 (the next), then tri
  bool positive;
  FaceTriangle* face;
};

// A face triangle's fold key, 24 i + own[code] (or next[code] for a -y or
// -z face triangle of the next row, whose face this row owns as its +y or
// +z face), by CornerTriangle::code (axis | side << 2 | missing corner <<
// 3 | positive << 5): x faces at position i + side, then axis * 8 + upper
// * 4 + missing corner. Bit c of always_owned: a row decides code c's face
// (x faces, its +y and +z faces); of lower[axis]: a -y (axis 1) or -z
// (axis 2) face, which a row owns only on the grid's border.
struct FoldKeys {
  std::uint8_t own[64] = {}, next[64] = {};
  std::uint64_t always_owned = 0, lower[3] = {};
};

inline const FoldKeys& fold_keys() {
  static constexpr FoldKeys keys = [] {
    FoldKeys t;
    for (unsigned c = 0; c < 64; ++c) {
      const unsigned axis = c & 3u, side = (c >> 2) & 1u, corner = (c >> 3) & 3u;
      if (axis == 3) continue;
      if (axis == 0) {
        t.own[c] = static_cast<std::uint8_t>(24 * side + corner);
        t.always_owned |= std::uint64_t{1} << c;
        continue;
      }
      t.own[c] = static_cast<std::uint8_t>(axis * 8 + side * 4 + corner);
      t.next[c] = static_cast<std::uint8_t>(axis * 8 + 4 + corner);
      if (side) t.always_owned |= std::uint64_t{1} << c;
      else t.lower[axis] |= std::uint64_t{1} << c;
    }
    return t;
  }();
  return keys;
}

// Decides the faces that voxel row (j, k) of a grid of `positions` points
// along x owns: the x faces between its voxels, its +y and +z faces (shared
// with rows (j + 1, k) and (j, k + 1), whose -y and -z face triangles are
// passed as `next_y` and `next_z`, empty when there is no such row), and its
// -y and -z faces when they lie on the grid's border (j == 0, k == 0). Marks the dropped face triangles of all
// three rows `folded`. Every face is owned by one row, so rows decided at
// once mark different triangles. Returns whether it marked any.
inline bool fold_across_faces(std::size_t positions, FaceTriangle* own, std::size_t n_own, bool j_first, bool k_first,
                              FaceTriangle* next_y, std::size_t n_next_y, FaceTriangle* next_z, std::size_t n_next_z,
                              std::vector<FoldEntry>& entries) {
  // key: ((face position along the row * 3 + axis) * 2 + upper) * 4 +
  // missing corner, that is 24 i + a number that depends on the record's
  // code alone (FoldKeys), with whether the row owns its face (else the
  // key is `sink`, past every key).
  const FoldKeys& keys = fold_keys();
  const std::uint64_t own_codes =
      keys.always_owned | (j_first ? keys.lower[1] : 0) | (k_first ? keys.lower[2] : 0);
  const std::uint64_t sink = 24 * positions;
  auto own_key = [&](const FaceTriangle& f) {
    return ((own_codes >> f.code) & 1u) ? 24 * std::uint64_t{f.i} + keys.own[f.code] : sink;
  };
  auto next_key = [&](const FaceTriangle& f, unsigned axis) {
    return ((keys.lower[axis] >> f.code) & 1u) ? 24 * std::uint64_t{f.i} + keys.next[f.code] : sink;
  };
  // Calls visit(key, row, face) for every face triangle of a face this row
  // owns, in mesh order (this row's, then the next rows').
  auto for_each_owned = [&](auto&& visit) {
    for (std::size_t e = 0; e < n_own; ++e)
      if (const std::uint64_t k = own_key(own[e]); k != sink) visit(k, 0u, own[e]);
    for (std::size_t e = 0; e < n_next_y; ++e)
      if (const std::uint64_t k = next_key(next_y[e], 1); k != sink) visit(k, 1u, next_y[e]);
    for (std::size_t e = 0; e < n_next_z; ++e)
      if (const std::uint64_t k = next_key(next_z[e], 2); k != sink) visit(k, 1u, next_z[e]);
  };
  // Most face triangles share their face with no other: the keys that occur
  // more than once are found by direct addressing first (a key names a face
  // position along the row: below 24 * positions; the slots stamped with
  // the call instead of cleared), with no entry built; only a row with such
  // keys lists their triangles, sorts and decides them. (Counting every
  // record without a branch, the faces a row does not own in the sink's
  // slot, was 3.6 M instructions more on ch2better.)
  struct Seen {
    std::uint32_t call = 0, count = 0;
  };
  thread_local std::vector<Seen> seen;
  thread_local std::uint32_t call = 0;
  if (seen.size() < sink) seen.resize(sink);  // new slots belong to no call
  if (++call == 0) std::fill(seen.begin(), seen.end(), Seen{}), call = 1;
  bool any = false;
  for_each_owned([&](std::uint64_t k, unsigned, FaceTriangle&) {
    Seen& slot = seen[k];
    if (slot.call == call) ++slot.count, any = true;
    else slot = {call, 1};
  });
  if (!any) return false;
  entries.clear();
  for_each_owned([&](std::uint64_t k, unsigned row, FaceTriangle& f) {
    if (seen[k].count > 1) entries.push_back({k, row, f.tri, ((f.code >> 5) & 1u) != 0, &f});
  });
  std::sort(entries.begin(), entries.end(), [](const FoldEntry& a, const FoldEntry& b) {
    return a.key != b.key ? a.key < b.key : a.row != b.row ? a.row < b.row : a.tri < b.tri;
  });
  bool marked = false;
  for (std::size_t b = 0; b < entries.size();) {
    std::size_t e = b + 1;
    while (e < entries.size() && entries[e].key == entries[b].key) ++e;
    resolve_equal_triangles(static_cast<int>(e - b), [&](int m) { return entries[b + m].positive; },
                            [&](int m) { entries[b + m].face->folded = 1, marked = true; });
    b = e;
  }
  return marked;
}

}  // namespace keymesh::generate
