#pragma once
// An atlas-like label map for the label tests: many labels in blobs a few
// voxels wide, three or more meeting all over (triple lines and corners),
// as in a brain atlas; the volumes on which smoothing folded before the
// fold guard (docs/decisions/labels-smoothing-folds.md).
#include <array>
#include <cstdint>
#include <vector>

#include "label_map.hpp"

namespace keymesh::test {

// Labels 1..labels: per voxel the label whose noise field is largest, the
// fields box-filtered `passes` times (blobs a few voxels wide; 0 passes:
// every voxel its own). splitmix64 noise, the same on every platform.
inline ImageGrid argmax_noise(std::array<Id, 3> n, int labels, std::uint64_t seed, int passes) {
  const Id count = n[0] * n[1] * n[2];
  std::vector<float> field(static_cast<std::size_t>(labels * count));
  std::uint64_t s = seed;
  for (float& f : field) {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    f = static_cast<float>((z ^ (z >> 31)) >> 40) / 16777216.0f;
  }
  const Id stride[3] = {1, n[0], n[0] * n[1]};
  std::vector<float> tmp(field.size());
  for (int p = 0; p < passes; ++p)
    for (int a = 0; a < 3; ++a) {
      for (Id v = 0; v < count; ++v) {
        const Id c = (v / stride[a]) % n[a];
        const Id lo = v + ((c + n[a] - 1) % n[a] - c) * stride[a], hi = v + ((c + 1) % n[a] - c) * stride[a];
        for (int l = 0; l < labels; ++l)
          tmp[l * count + v] = (field[l * count + lo] + field[l * count + v] + field[l * count + hi]) / 3;
      }
      field.swap(tmp);
    }
  return label_map(n, [&](Id i, Id j, Id k) {
    const Id v = i + j * stride[1] + k * stride[2];
    int best = 0;
    for (int l = 1; l < labels; ++l)
      if (field[l * count + v] > field[best * count + v]) best = l;
    return best + 1;
  });
}

}  // namespace keymesh::test
