#pragma once
// Inside/outside bits of a voxel grid, one bit per sample, and the walk over
// the cut voxels of a voxel row: the classification that both of the
// contour's partition plans start from (src/generate/contour.cpp,
// src/generate/contour_rows.hpp). Internal to src/generate.
#include <bit>
#include <cstdint>
#include <cstring>
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/generate/contour_kernels.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh::generate {

// Inside bits of every grid row (j, k), one bit per sample, plus one zero
// word of padding so that "bit i + 1" can always be read.
struct InsideBits {
  Id words_per_row = 0;
  std::vector<std::uint64_t> words;
  const std::uint64_t* row(Id j, Id k, Id ny) const { return words.data() + (k * ny + j) * words_per_row; }
};

template <class T>
void classify(const T* samples, const GridShape& s, const InsideTest<T>& test, InsideBits& bits) {
  bits.words_per_row = (s.nx + 63) / 64 + 1;
  bits.words.assign(static_cast<std::size_t>(bits.words_per_row * s.ny * s.nz), 0);
  const Id rows = s.ny * s.nz;
  const Id full = s.nx / 64;
  const Id wpr = bits.words_per_row;
  parallel::for_each(rows, [&](Id r) {
    const T* in = samples + r * s.nx;
    std::uint64_t* out = bits.words.data() + r * wpr;
    if (test.none) return;
    if (test.all) {
      for (Id i = 0; i < s.nx; ++i) out[i >> 6] |= std::uint64_t{1} << (i & 63);
      return;
    }
    const T thr = test.threshold;
    for (Id q = 0; q < full; ++q) {
      // Compare into bytes (a loop the compiler vectorizes), then pack each
      // 8 bytes of 0/1 into 8 bits with one multiply: byte i lands on bit
      // 56 + i of the product, with no carries between the terms.
      const T* v = in + 64 * q;
      alignas(64) std::uint8_t flag[64];
      for (int b = 0; b < 64; ++b) flag[b] = static_cast<std::uint8_t>(v[b] >= thr);
      std::uint64_t w = 0;
      for (int g = 0; g < 8; ++g) {
        std::uint64_t x;
        std::memcpy(&x, flag + 8 * g, 8);
        w |= ((x * 0x0102040810204080ull) >> 56) << (8 * g);
      }
      out[q] = w;
    }
    std::uint64_t w = 0;
    for (Id i = 64 * full; i < s.nx; ++i) w |= static_cast<std::uint64_t>(in[i] >= thr) << (i & 63);
    if (s.nx % 64) out[full] = w;
  }, 64);
}

// Visits every voxel of voxel row (j, k) whose corners are not all on one
// side, in increasing i, calling f(i, cube_case). Whole 64-voxel words with
// no sign change are skipped with a few bit operations.
template <class F>
void for_each_cut_voxel(const InsideBits& bits, const GridShape& s, Id j, Id k, F&& f) {
  const std::uint64_t* r00 = bits.row(j, k, s.ny);
  const std::uint64_t* r10 = bits.row(j + 1, k, s.ny);
  const std::uint64_t* r01 = bits.row(j, k + 1, s.ny);
  const std::uint64_t* r11 = bits.row(j + 1, k + 1, s.ny);
  const Id voxels = s.nx - 1;
  const Id words = (voxels + 63) / 64;
  for (Id q = 0; q < words; ++q) {
    const std::uint64_t a = r00[q], b = r10[q], c = r01[q], d = r11[q];
    // Bits of corner i + 1: shift the next word in.
    const std::uint64_t a1 = (a >> 1) | (r00[q + 1] << 63);
    const std::uint64_t b1 = (b >> 1) | (r10[q + 1] << 63);
    const std::uint64_t c1 = (c >> 1) | (r01[q + 1] << 63);
    const std::uint64_t d1 = (d >> 1) | (r11[q + 1] << 63);
    std::uint64_t active = (a ^ b) | (a ^ c) | (a ^ d) | (a ^ a1) | (a ^ b1) | (a ^ c1) | (a ^ d1);
    const Id left = voxels - 64 * q;
    if (left < 64) active &= (std::uint64_t{1} << left) - 1;
    while (active) {
      const int bit = std::countr_zero(active);
      active &= active - 1;
      // Corners i and i + 1 of a row are bits `bit` and `bit + 1` of its
      // word, two bits in case order, read with one shift; only bit 63 takes
      // corner i + 1 from the next word.
      const unsigned cube_case =
          bit < 63 ? static_cast<unsigned>(((a >> bit) & 3) | (((b >> bit) & 3) << 2) | (((c >> bit) & 3) << 4) |
                                           (((d >> bit) & 3) << 6))
                   : static_cast<unsigned>((a >> 63) | ((a1 >> 63) << 1) | ((b >> 63) << 2) | ((b1 >> 63) << 3) |
                                           ((c >> 63) << 4) | ((c1 >> 63) << 5) | ((d >> 63) << 6) |
                                           ((d1 >> 63) << 7));
      f(64 * q + bit, cube_case);
    }
  }
}

}  // namespace keymesh::generate
