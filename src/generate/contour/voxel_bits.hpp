#pragma once
// Inside/outside bits of a voxel grid, one bit per sample, and the walk over
// the cut voxels of a voxel row: the classification that both of the
// contour's partition plans start from (src/generate/contour/contour.cpp,
// src/generate/contour/contour_rows.hpp). Internal to src/generate.
#include <bit>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "keymesh/core/types.hpp"
#include "keymesh/generate/contour/contour_kernels.hpp"
#include "keymesh/parallel/for_each.hpp"
#include "keymesh/parallel/fresh_memory.hpp"

namespace keymesh::generate {

// Inside bits of every grid row (j, k), one bit per sample, plus one zero
// word of padding so that "bit i + 1" can always be read.
struct InsideBits {
  Id words_per_row = 0;
  std::vector<std::uint64_t> words;
  const std::uint64_t* row(Id j, Id k, Id ny) const { return words.data() + (k * ny + j) * words_per_row; }
};

// Bit b of the result: v[b] >= thr, for b in [0, 64). NaN is outside, as
// in InsideTest. uint8 and float samples (the volumes people contour most)
// are compared 16 at a time with SSE2 and their sign bits gathered with one
// movemask per 16; other types by bytes packed with a multiply.
template <class T>
std::uint64_t inside_word(const T* v, T thr) {
  std::uint64_t w = 0;
#if defined(__SSE2__)
  if constexpr (std::is_same_v<T, std::uint8_t>) {
    const __m128i t = _mm_set1_epi8(static_cast<char>(thr));
    for (int g = 0; g < 4; ++g) {
      const __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(v + 16 * g));
      // Unsigned x >= t exactly when max(x, t) is x.
      const int m = _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_max_epu8(x, t), x));
      w |= static_cast<std::uint64_t>(static_cast<std::uint16_t>(m)) << (16 * g);
    }
    return w;
  } else if constexpr (std::is_same_v<T, float>) {
    const __m128 t = _mm_set1_ps(thr);
    for (int g = 0; g < 4; ++g) {
      // Ordered compares (false for NaN), 4 x int32 of all ones or zeros,
      // narrowed with signed saturation to 16 bytes in sample order.
      __m128i q[4];
      for (int h = 0; h < 4; ++h) q[h] = _mm_castps_si128(_mm_cmpge_ps(_mm_loadu_ps(v + 16 * g + 4 * h), t));
      const __m128i bytes = _mm_packs_epi16(_mm_packs_epi32(q[0], q[1]), _mm_packs_epi32(q[2], q[3]));
      w |= static_cast<std::uint64_t>(static_cast<std::uint16_t>(_mm_movemask_epi8(bytes))) << (16 * g);
    }
    return w;
  }
#endif
  // Compare into bytes (a loop the compiler vectorizes), then pack each 8
  // bytes of 0/1 into 8 bits with one multiply: byte i lands on bit 56 + i
  // of the product, with no carries between the terms.
  alignas(64) std::uint8_t flag[64];
  for (int b = 0; b < 64; ++b) flag[b] = static_cast<std::uint8_t>(v[b] >= thr);
  for (int g = 0; g < 8; ++g) {
    std::uint64_t x;
    std::memcpy(&x, flag + 8 * g, 8);
    w |= ((x * 0x0102040810204080ull) >> 56) << (8 * g);
  }
  return w;
}

// Writes every word of `bits` (samples, padding), so storage kept from an
// earlier call is reused as it is: no zero-fill, no fresh pages. Storage
// that has to grow gets huge pages and a parallel first touch.
template <class T>
void classify(const T* samples, const GridShape& s, const InsideTest<T>& test, InsideBits& bits) {
  bits.words_per_row = (s.nx + 63) / 64 + 1;
  parallel::resize_fresh(bits.words, static_cast<std::size_t>(bits.words_per_row * s.ny * s.nz));
  const Id rows = s.ny * s.nz;
  const Id full = s.nx / 64, rest = s.nx % 64;
  const Id wpr = bits.words_per_row;
  const std::uint64_t rest_mask = (std::uint64_t{1} << rest) - 1;
  parallel::for_each(rows, [&](Id r) {
    const T* in = samples + r * s.nx;
    std::uint64_t* out = bits.words.data() + r * wpr;
    out[wpr - 1] = 0;  // the padding word: "bit i + 1" of the last sample
    if (test.none || test.all) {
      const std::uint64_t word = test.all ? ~std::uint64_t{0} : 0;
      for (Id q = 0; q < full; ++q) out[q] = word;
      if (rest) out[full] = word & rest_mask;
      return;
    }
    const T thr = test.threshold;
    for (Id q = 0; q < full; ++q) out[q] = inside_word(in + 64 * q, thr);
    if (rest) {
      // The row's last samples, padded to a word: the padding's bits are
      // cleared (no sample there).
      T tail[64] = {};
      std::memcpy(tail, in + 64 * full, static_cast<std::size_t>(rest) * sizeof(T));
      out[full] = inside_word(tail, thr) & rest_mask;
    }
  }, 64);
}

// Visits every voxel of voxel row (j, k) whose corners are not all on one
// side, in increasing i, calling f(i, case_of(bit, corners)), `corners` the
// row words of its four corner rows (a, b, c, d: rows (j, k), (j + 1, k),
// (j, k + 1), (j + 1, k + 1)) and those shifted to corner i + 1 (a1 ..
// d1), `bit` its bit in them. Whole 64-voxel words with no sign change are
// skipped with a few bit operations.
struct CornerWords {
  std::uint64_t a, b, c, d, a1, b1, c1, d1;
};
// Calls word(q, w, active) for every 64-voxel word q of voxel row (j, k)
// holding cut voxels: w its corner words, bit b of `active` voxel 64 q + b
// cut.
template <class Word>
void for_each_cut_word(const InsideBits& bits, const GridShape& s, Id j, Id k, Word&& word) {
  const std::uint64_t* r00 = bits.row(j, k, s.ny);
  const std::uint64_t* r10 = bits.row(j + 1, k, s.ny);
  const std::uint64_t* r01 = bits.row(j, k + 1, s.ny);
  const std::uint64_t* r11 = bits.row(j + 1, k + 1, s.ny);
  const Id voxels = s.nx - 1;
  const Id words = (voxels + 63) / 64;
  for (Id q = 0; q < words; ++q) {
    CornerWords w;
    w.a = r00[q], w.b = r10[q], w.c = r01[q], w.d = r11[q];
    // Bits of corner i + 1: shift the next word in.
    w.a1 = (w.a >> 1) | (r00[q + 1] << 63);
    w.b1 = (w.b >> 1) | (r10[q + 1] << 63);
    w.c1 = (w.c >> 1) | (r01[q + 1] << 63);
    w.d1 = (w.d >> 1) | (r11[q + 1] << 63);
    const std::uint64_t a = w.a;
    std::uint64_t active = (a ^ w.b) | (a ^ w.c) | (a ^ w.d) | (a ^ w.a1) | (a ^ w.b1) | (a ^ w.c1) | (a ^ w.d1);
    const Id left = voxels - 64 * q;
    if (left < 64) active &= (std::uint64_t{1} << left) - 1;
    if (active) word(q, w, active);
  }
}

template <class CaseOf, class F>
void for_each_cut_voxel(const InsideBits& bits, const GridShape& s, Id j, Id k, CaseOf&& case_of, F&& f) {
  for_each_cut_word(bits, s, j, k, [&](Id q, const CornerWords& w, std::uint64_t active) {
    while (active) {
      const int bit = std::countr_zero(active);
      active &= active - 1;
      f(64 * q + bit, case_of(bit, w));
    }
  });
}

// The cube case of the voxel at `bit` of corner words w: corners i and i + 1
// of a row are bits `bit` and `bit + 1` of its word, two bits in case order,
// read with one shift; only bit 63 takes corner i + 1 from the next word.
inline unsigned cube_case_at(int bit, const CornerWords& w) {
  return bit < 63 ? static_cast<unsigned>(((w.a >> bit) & 3) | (((w.b >> bit) & 3) << 2) | (((w.c >> bit) & 3) << 4) |
                                          (((w.d >> bit) & 3) << 6))
                  : static_cast<unsigned>((w.a >> 63) | ((w.a1 >> 63) << 1) | ((w.b >> 63) << 2) |
                                          ((w.b1 >> 63) << 3) | ((w.c >> 63) << 4) | ((w.c1 >> 63) << 5) |
                                          ((w.d >> 63) << 6) | ((w.d1 >> 63) << 7));
}

// Eight words' bits by position: bit r of bytes[b] is bit b of word r
// (w0 .. w7). The words' bytes are interleaved so that each 64-bit lane
// holds eight positions' bytes of the eight words (byte r: word r), and
// every lane's 8 x 8 bit matrix is transposed (Hacker's Delight,
// transpose8). About 100 instructions for 64 positions, against some 20 a
// position one at a time.
inline void bytes_of_words(std::uint64_t w0, std::uint64_t w1, std::uint64_t w2, std::uint64_t w3, std::uint64_t w4,
                           std::uint64_t w5, std::uint64_t w6, std::uint64_t w7, std::uint8_t bytes[64]) {
#if defined(__SSE2__)
  auto pairs = [](std::uint64_t lo, std::uint64_t hi) {
    const __m128i p = _mm_set_epi64x(static_cast<long long>(hi), static_cast<long long>(lo));
    return _mm_unpacklo_epi8(p, _mm_srli_si128(p, 8));  // lo's byte g, hi's byte g, ... for g = 0..7
  };
  const __m128i a = pairs(w0, w1), b = pairs(w2, w3), c = pairs(w4, w5), d = pairs(w6, w7);
  const __m128i ab_lo = _mm_unpacklo_epi16(a, b), ab_hi = _mm_unpackhi_epi16(a, b);
  const __m128i cd_lo = _mm_unpacklo_epi16(c, d), cd_hi = _mm_unpackhi_epi16(c, d);
  // Lane pairs of groups (0, 1), (2, 3), (4, 5), (6, 7): each lane one group's eight rows.
  __m128i x[4] = {_mm_unpacklo_epi32(ab_lo, cd_lo), _mm_unpackhi_epi32(ab_lo, cd_lo), _mm_unpacklo_epi32(ab_hi, cd_hi),
                  _mm_unpackhi_epi32(ab_hi, cd_hi)};
  const __m128i m7 = _mm_set1_epi64x(0x00AA00AA00AA00AALL), m14 = _mm_set1_epi64x(0x0000CCCC0000CCCCLL),
                m28 = _mm_set1_epi64x(0x00000000F0F0F0F0LL);
  for (__m128i& v : x) {
    __m128i t = _mm_and_si128(_mm_xor_si128(v, _mm_srli_epi64(v, 7)), m7);
    v = _mm_xor_si128(v, _mm_xor_si128(t, _mm_slli_epi64(t, 7)));
    t = _mm_and_si128(_mm_xor_si128(v, _mm_srli_epi64(v, 14)), m14);
    v = _mm_xor_si128(v, _mm_xor_si128(t, _mm_slli_epi64(t, 14)));
    t = _mm_and_si128(_mm_xor_si128(v, _mm_srli_epi64(v, 28)), m28);
    v = _mm_xor_si128(v, _mm_xor_si128(t, _mm_slli_epi64(t, 28)));
  }
  for (int i = 0; i < 4; ++i) _mm_storeu_si128(reinterpret_cast<__m128i*>(bytes + 16 * i), x[i]);
#else
  const std::uint64_t w[8] = {w0, w1, w2, w3, w4, w5, w6, w7};
  for (int b = 0; b < 64; ++b) {
    unsigned byte = 0;
    for (int r = 0; r < 8; ++r) byte |= static_cast<unsigned>((w[r] >> b) & 1u) << r;
    bytes[b] = static_cast<std::uint8_t>(byte);
  }
#endif
}

// The cube cases of all 64 voxels of corner words w at once: cases[b] is
// cube_case_at(b, w). Bit r of case b is bit b of the r-th of the eight
// words (a, a1, b, b1, ...), so the cases are those words' bytes by
// position: the dense words' way.
inline void cube_cases_of_word(const CornerWords& w, std::uint8_t cases[64]) {
  bytes_of_words(w.a, w.a1, w.b, w.b1, w.c, w.c1, w.d, w.d1, cases);
}

// Calls f(bit, cube_case) for every voxel `bit` of `active` (cut voxels of
// a word with corner words w), in increasing bit: the cases made one at a
// time in words with few cut voxels, all 64 at once (cube_cases_of_word)
// in words with many (a dense surface's).
template <class F>
[[gnu::always_inline]] inline void for_each_case_of_word(const CornerWords& w, std::uint64_t active, F&& f) {
  constexpr int kDense = 4;  // cut voxels in a word from which its cases are made at once
  if (std::popcount(active) >= kDense) {
    std::uint8_t cases[64];
    cube_cases_of_word(w, cases);
    for (; active; active &= active - 1) {
      const int bit = std::countr_zero(active);
      f(bit, unsigned{cases[bit]});
    }
    return;
  }
  for (; active; active &= active - 1) {
    const int bit = std::countr_zero(active);
    f(bit, cube_case_at(bit, w));
  }
}

// for_each_cut_voxel with each voxel's cube case computed from the bits
// (for_each_case_of_word).
template <class F>
void for_each_cut_voxel(const InsideBits& bits, const GridShape& s, Id j, Id k, F&& f) {
  for_each_cut_word(bits, s, j, k, [&](Id q, const CornerWords& w, std::uint64_t active) {
    for_each_case_of_word(w, active, [&](int bit, unsigned cube_case) { f(64 * q + bit, cube_case); });
  });
}

}  // namespace keymesh::generate
