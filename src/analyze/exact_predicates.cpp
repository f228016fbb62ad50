#include "keymesh/analyze/exact_predicates.hpp"

#include <gmp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace keymesh::analyze {

namespace {

constexpr double kEpsilon = 0x1p-53;  // half an ulp of 1.0: double's unit roundoff
// Shewchuk's bounds on the rounding error of the double evaluation, relative
// to the permanent (the same expression with absolute values); rounded up.
constexpr double kOrient3dBound = (7.0 + 56.0 * kEpsilon) * kEpsilon;
constexpr double kOrient2dBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;

// GCC's and Clang's 128-bit integers (__extension__: not ISO C++, said on purpose).
__extension__ typedef __int128 Int128;
__extension__ typedef unsigned __int128 UInt128;

// The floats of one predicate as integers times one common power of two:
// v = m * 2^(exponent - 24) with |m| < 2^24 for every float (frexp), all
// scaled to the smallest exponent among them. Exact for every finite float.
template <std::size_t N>
struct ScaledInts {
  std::array<std::int64_t, N> mantissa{};
  std::array<int, N> shift{};  // left shift of each mantissa to the common unit
  int max_shift = 0;

  explicit ScaledInts(const std::array<float, N>& v) {
    // Sign, 24-bit significand and exponent straight from the bits (a
    // subnormal has no hidden bit and the smallest exponent).
    std::array<int, N> exponent{};
    int low = std::numeric_limits<int>::max();
    for (std::size_t i = 0; i < N; ++i) {
      std::uint32_t bits = 0;
      std::memcpy(&bits, &v[i], sizeof bits);
      const int biased = static_cast<int>((bits >> 23) & 0xff);
      const std::int64_t significand = (bits & 0x7fffff) | (biased ? 0x800000u : 0u);
      mantissa[i] = (bits >> 31) ? -significand : significand;
      exponent[i] = biased ? biased : 1;
      if (significand != 0) low = std::min(low, exponent[i]);
    }
    for (std::size_t i = 0; i < N; ++i) {
      shift[i] = mantissa[i] != 0 ? exponent[i] - low : 0;
      max_shift = std::max(max_shift, shift[i]);
    }
  }
  // Every scaled value fits a signed 128-bit integer with room for a difference.
  bool fits_int128() const { return max_shift <= 24 * 4; }
  Int128 value(std::size_t i) const { return static_cast<Int128>(mantissa[i]) << shift[i]; }
  void value(std::size_t i, mpz_t out) const {
    mpz_set_si(out, static_cast<long>(mantissa[i]));
    mpz_mul_2exp(out, out, static_cast<mp_bitcnt_t>(shift[i]));
  }
};

int bits_of(Int128 v) {
  const UInt128 u = v < 0 ? -static_cast<UInt128>(v) : static_cast<UInt128>(v);
  const auto high = static_cast<std::uint64_t>(u >> 64), low = static_cast<std::uint64_t>(u);
  return high ? 128 - __builtin_clzll(high) : (low ? 64 - __builtin_clzll(low) : 0);
}

template <class T>
int sign_of(const T& v) {
  return (v > 0) - (v < 0);
}

// det[u; v; w] of three difference vectors given as 9 values.
template <class T>
T det3(const T* d) {
  return d[0] * (d[4] * d[8] - d[5] * d[7]) - d[1] * (d[3] * d[8] - d[5] * d[6]) +
         d[2] * (d[3] * d[7] - d[4] * d[6]);
}

class Mpz {
 public:
  Mpz() { mpz_init(v_); }
  ~Mpz() { mpz_clear(v_); }
  Mpz(const Mpz&) = delete;
  Mpz& operator=(const Mpz&) = delete;
  mpz_ptr get() { return v_; }

 private:
  mpz_t v_;
};

int orient3d_exact(const float* a, const float* b, const float* c, const float* d) {
  const ScaledInts<12> s({a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], d[0], d[1], d[2]});
  if (s.fits_int128()) {
    std::array<Int128, 9> diff{};
    int bits = 0;
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) {
        diff[3 * r + k] = s.value(3 * (r + 1) + k) - s.value(k);
        bits = std::max(bits, bits_of(diff[3 * r + k]));
      }
    // Three products of three factors and their sums stay under 2^127.
    if (bits <= 41) return sign_of(det3(diff.data()));
  }
  std::array<Mpz, 9> diff;
  Mpz origin, t0, t1, det;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) {
      s.value(k, origin.get());
      s.value(3 * (r + 1) + k, diff[3 * r + k].get());
      mpz_sub(diff[3 * r + k].get(), diff[3 * r + k].get(), origin.get());
    }
  auto minor = [&](int p, int q, int r, int u, mpz_ptr out) {  // diff[p]*diff[q] - diff[r]*diff[u]
    mpz_mul(out, diff[p].get(), diff[q].get());
    mpz_mul(t1.get(), diff[r].get(), diff[u].get());
    mpz_sub(out, out, t1.get());
  };
  minor(4, 8, 5, 7, t0.get());
  mpz_mul(det.get(), diff[0].get(), t0.get());
  minor(3, 8, 5, 6, t0.get());
  mpz_submul(det.get(), diff[1].get(), t0.get());
  minor(3, 7, 4, 6, t0.get());
  mpz_addmul(det.get(), diff[2].get(), t0.get());
  return mpz_sgn(det.get());
}

int orient2d_exact(float ax, float ay, float bx, float by, float cx, float cy) {
  const ScaledInts<6> s({ax, ay, bx, by, cx, cy});
  if (s.fits_int128()) {
    const Int128 ux = s.value(2) - s.value(0), uy = s.value(3) - s.value(1);
    const Int128 vx = s.value(4) - s.value(0), vy = s.value(5) - s.value(1);
    if (std::max({bits_of(ux), bits_of(uy), bits_of(vx), bits_of(vy)}) <= 62) return sign_of(ux * vy - uy * vx);
  }
  std::array<Mpz, 6> v;
  for (std::size_t i = 0; i < 6; ++i) s.value(i, v[i].get());
  Mpz u, w, det, t;
  mpz_sub(u.get(), v[2].get(), v[0].get());  // ux
  mpz_sub(w.get(), v[5].get(), v[1].get());  // vy
  mpz_mul(det.get(), u.get(), w.get());
  mpz_sub(u.get(), v[3].get(), v[1].get());  // uy
  mpz_sub(w.get(), v[4].get(), v[0].get());  // vx
  mpz_mul(t.get(), u.get(), w.get());
  mpz_sub(det.get(), det.get(), t.get());
  return mpz_sgn(det.get());
}

}  // namespace

int orient3d(const float* a, const float* b, const float* c, const float* d) {
  const double ux = double(b[0]) - a[0], uy = double(b[1]) - a[1], uz = double(b[2]) - a[2];
  const double vx = double(c[0]) - a[0], vy = double(c[1]) - a[1], vz = double(c[2]) - a[2];
  const double wx = double(d[0]) - a[0], wy = double(d[1]) - a[1], wz = double(d[2]) - a[2];
  const double m0 = vy * wz, m1 = vz * wy, m2 = vx * wz, m3 = vz * wx, m4 = vx * wy, m5 = vy * wx;
  const double det = ux * (m0 - m1) - uy * (m2 - m3) + uz * (m4 - m5);
  const double permanent = std::fabs(ux) * (std::fabs(m0) + std::fabs(m1)) +
                           std::fabs(uy) * (std::fabs(m2) + std::fabs(m3)) +
                           std::fabs(uz) * (std::fabs(m4) + std::fabs(m5));
  const double bound = kOrient3dBound * permanent;
  if (det > bound) return 1;
  if (det < -bound) return -1;
  if (permanent == 0) return 0;  // every difference along some row or column is zero
  // Four points with one coordinate in common lie in that axis plane: a
  // grid face, where a contour's points are often (the filter cannot tell 0).
  for (int k = 0; k < 3; ++k)
    if (a[k] == b[k] && a[k] == c[k] && a[k] == d[k]) return 0;
  return orient3d_exact(a, b, c, d);
}

int orient2d(const float* a, const float* b, const float* c, int drop) {
  const int i = (drop + 1) % 3, j = (drop + 2) % 3;
  const double ux = double(b[i]) - a[i], uy = double(b[j]) - a[j];
  const double vx = double(c[i]) - a[i], vy = double(c[j]) - a[j];
  const double l = ux * vy, r = uy * vx, det = l - r;
  const double bound = kOrient2dBound * (std::fabs(l) + std::fabs(r));
  if (det > bound) return 1;
  if (det < -bound) return -1;
  if (l == 0 && r == 0) return 0;
  return orient2d_exact(a[i], a[j], b[i], b[j], c[i], c[j]);
}

}  // namespace keymesh::analyze
