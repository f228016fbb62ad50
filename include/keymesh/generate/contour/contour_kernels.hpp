#pragma once
// The per-element functors of marching cubes on a voxel grid, shared by the
// CPU fast path (src/generate/contour/contour.cpp) and the device path
// (contour_device.hpp, which src/cuda runs on the GPU): plain values and KEYMESH_HD
// functions, no allocation, so the same arithmetic (hence the same bits) runs on both.
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "keymesh/core/device.hpp"
#include "keymesh/core/types.hpp"
#include "keymesh/generate/contour/marching_cubes_table.hpp"
#include "keymesh/mesh/face_normal.hpp"

// The per-point arithmetic the CPU passes call for every point or grid
// point, inlined into their loops (GCC left these as calls, ~10 % of a
// gradient-normal contour's instructions in call overhead).
#if defined(__CUDACC__)
#define KEYMESH_HOT_INLINE __forceinline__
#else
#define KEYMESH_HOT_INLINE [[gnu::always_inline]] inline
#endif

namespace keymesh::generate {

// The inside test `value >= iso` in the sample's own type, so the hot loop
// compares samples without converting them: for floats the threshold is the
// smallest float >= iso, for integers ceil(iso) clamped to the type's range.
template <class T>
struct InsideTest {
  T threshold{};
  bool none = false;  // no sample can be inside
  bool all = false;   // every sample is inside

  explicit InsideTest(double iso) {
    if constexpr (std::is_same_v<T, double>) {
      threshold = iso;
    } else if constexpr (std::is_same_v<T, float>) {
      float f = static_cast<float>(iso);
      if (static_cast<double>(f) < iso) f = std::nextafter(f, std::numeric_limits<float>::infinity());
      threshold = f;
    } else {
      const double c = std::ceil(iso);
      if (c > static_cast<double>(std::numeric_limits<T>::max())) none = true;
      else if (c <= static_cast<double>(std::numeric_limits<T>::lowest())) all = true;
      else threshold = static_cast<T>(c);
    }
  }
};


// Geometry of the grid as the functors need it (plain values: device-friendly).
struct GridShape {
  Id nx, ny, nz, nxy, n;
  double origin[3], spacing[3];
  Id stride[3];
  // When the grid is a box of a larger grid, starting at its grid point
  // (offset[0], offset[1], offset[2]) (a streamed slab: offset[2] only; a
  // Dask block: any): positions are computed from the larger grid's
  // indices, so the box gives the bits the whole grid gives.
  Id offset[3];
  // The case table: marching_cubes_table(reversed_axes), as
  // ContourOptions::reversed_axes asks (coarsening's tables follow it).
  const MarchingCubesTable* table;
  bool reversed_axes;
};

// Position, scalar and gradient of the point on the edge named by a key.
template <class T>
struct EdgeInterpolator {
  const T* samples;
  GridShape s;
  const double* isovalues;
  Id keys_per_iso;  // 3N

  // Whole-number samples of 32 bits or less: a difference (or a sum of a
  // few) of their doubles is exact, hence equal to the integers' converted.
  static constexpr bool kSmallIntegers = std::is_integral_v<T> && sizeof(T) <= 4;

  struct Point {
    Id p0;       // the edge's first grid point
    Id ijk[3];   // its grid coordinates
    int axis;    // the edge's direction
    double t, iso;
  };

  // Divisions by run-time values are the cost here (a million points, a few
  // each): single isovalue skips one, and i, j, k come from two.
  KEYMESH_HD Point locate(std::uint64_t key) const {
    Id iso_index = 0;
    Id edge = static_cast<Id>(key);
    if (static_cast<std::uint64_t>(edge) >= static_cast<std::uint64_t>(keys_per_iso)) {
      iso_index = edge / keys_per_iso;
      edge -= iso_index * keys_per_iso;
    }
    const Id p0 = edge / 3;
    const Id k = p0 / s.nxy;
    const Id rem = p0 - k * s.nxy;
    const Id j = rem / s.nx;
    return at(p0, rem - j * s.nx, j, k, static_cast<int>(edge - 3 * p0), iso_index);
  }

  // The point on the edge from grid point p0 = (i, j, k) along `axis`, when
  // its grid coordinates are known (no divisions): what locate() returns for
  // the edge's key.
  KEYMESH_HD Point at(Id p0, Id i, Id j, Id k, int axis, Id iso_index) const {
    Point p{};
    p.p0 = p0;
    p.axis = axis;
    p.iso = isovalues[iso_index];
    p.ijk[0] = i;
    p.ijk[1] = j;
    p.ijk[2] = k;
    const double v0 = static_cast<double>(samples[p.p0]);
    const double v1 = static_cast<double>(samples[p.p0 + s.stride[p.axis]]);
    const double t = (p.iso - v0) / (v1 - v0);
    if constexpr (std::is_integral_v<T>) {
      // Integer samples are exact in double and the edge is cut (one end
      // >= ceil(iso), the other below iso): t is finite and in (0, 1], so
      // the clamp below would change nothing.
      p.t = t;
    } else {
      // A NaN end sample (outside by definition) gives no crossing to
      // interpolate: place the point midway rather than emit NaN.
      p.t = std::isfinite(t) ? (t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t)) : 0.5;
    }
    return p;
  }

  KEYMESH_HD void position(const Point& p, float* xyz) const {
    // Grid coordinates: the edge's first grid point moved by t along the
    // edge's axis (the other two stay whole numbers).
    double u[3] = {static_cast<double>(p.ijk[0] + s.offset[0]), static_cast<double>(p.ijk[1] + s.offset[1]),
                   static_cast<double>(p.ijk[2] + s.offset[2])};
    u[p.axis] += p.t;
    for (int a = 0; a < 3; ++a) xyz[a] = static_cast<float>(s.origin[a] + s.spacing[a] * u[a]);
  }

  KEYMESH_HD float scalar(const Point& p) const {
    const double v0 = static_cast<double>(samples[p.p0]);
    const double v1 = static_cast<double>(samples[p.p0 + s.stride[p.axis]]);
    const double v = v0 + p.t * (v1 - v0);
    // Integer samples give a finite v (t finite in (0, 1], see at()).
    if constexpr (std::is_integral_v<T>) return static_cast<float>(v);
    else return static_cast<float>(std::isfinite(v) ? v : p.iso);
  }

  // Central-difference gradient at grid point `id` = (i, j, k), one-sided at the border.
  KEYMESH_HD void gradient_at(Id id, const Id ijk[3], double g[3]) const {
    if (interior(ijk)) interior_gradient(id, g);
    else border_gradient(id, ijk, g);
  }

  // Gradient and Hessian (xx, yy, zz, xy, xz, yz) at grid point `id`, by
  // central differences with indices clamped at the border.
  KEYMESH_HD void derivatives_at(Id id, const Id ijk[3], double g[3], double h[6]) const {
    if (interior(ijk)) interior_derivatives(id, g, h);
    else border_derivatives(id, ijk, g, h);
  }

  // Whether grid point (i, j, k) has both neighbours along every axis
  // (almost every point): its derivatives need no border test.
  KEYMESH_HD bool interior(const Id ijk[3]) const {
    return ijk[0] > 0 && ijk[0] + 1 < s.nx && ijk[1] > 0 && ijk[1] + 1 < s.ny && ijk[2] > 0 && ijk[2] + 1 < s.nz;
  }

  // gradient_at of an interior point: the spans border_gradient computes
  // for two neighbours, without its tests.
  KEYMESH_HOT_INLINE KEYMESH_HD void interior_gradient(Id id, double g[3]) const {
    for (int a = 0; a < 3; ++a) g[a] = slope(id - s.stride[a], id + s.stride[a], 2.0 * s.spacing[a]);
  }

  KEYMESH_HD void border_gradient(Id id, const Id ijk[3], double g[3]) const {
    const Id dims[3] = {s.nx, s.ny, s.nz};
    for (int a = 0; a < 3; ++a) {
      const bool has_lo = ijk[a] > 0, has_hi = ijk[a] + 1 < dims[a];
      const Id lo = has_lo ? id - s.stride[a] : id;
      const Id hi = has_hi ? id + s.stride[a] : id;
      g[a] = slope(lo, hi, static_cast<double>(int(has_lo) + int(has_hi)) * s.spacing[a]);
    }
  }

  // (samples[hi] - samples[lo]) / span, 0 where that is no finite slope.
  KEYMESH_HOT_INLINE KEYMESH_HD double slope(Id lo, Id hi, double span) const {
    double dv;
    if constexpr (kSmallIntegers)
      dv = static_cast<double>(static_cast<std::int64_t>(samples[hi]) - static_cast<std::int64_t>(samples[lo]));
    else
      dv = static_cast<double>(samples[hi]) - static_cast<double>(samples[lo]);
    return span > 0 && (std::is_integral_v<T> || std::isfinite(dv)) ? dv / span : 0.0;
  }

  // derivatives_at of an interior point: every neighbour there, no index
  // to clamp. For samples of 32 bits or less, whole numbers: the sums of
  // border_derivatives are exact in double (below 2^53), so they are made
  // in integers and converted once.
  KEYMESH_HOT_INLINE KEYMESH_HD void interior_derivatives(Id id, double g[3], double h[6]) const {
    interior_gradient(id, g);
    const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    if constexpr (kSmallIntegers) {
      auto v = [&](Id q) { return static_cast<std::int64_t>(samples[q]); };
      const std::int64_t f0 = v(id);
      for (int a = 0; a < 3; ++a) {
        const Id d = s.stride[a];
        h[a] = static_cast<double>(v(id + d) - 2 * f0 + v(id - d)) / (s.spacing[a] * s.spacing[a]);
      }
      for (int k = 0; k < 3; ++k) {
        const int a = pairs[k][0], b = pairs[k][1];
        const Id da = s.stride[a], db = s.stride[b];
        h[3 + k] = static_cast<double>(v(id + da + db) - v(id + da - db) - v(id - da + db) + v(id - da - db)) /
                   (4 * s.spacing[a] * s.spacing[b]);
      }
    } else {
      const double f0 = static_cast<double>(samples[id]);
      auto v = [&](Id q) {
        const double x = static_cast<double>(samples[q]);
        return std::isfinite(x) ? x : f0;
      };
      for (int a = 0; a < 3; ++a) {
        const Id d = s.stride[a];
        h[a] = (v(id + d) - 2 * f0 + v(id - d)) / (s.spacing[a] * s.spacing[a]);
      }
      for (int k = 0; k < 3; ++k) {
        const int a = pairs[k][0], b = pairs[k][1];
        const Id da = s.stride[a], db = s.stride[b];
        h[3 + k] = (v(id + da + db) - v(id + da - db) - v(id - da + db) + v(id - da - db)) /
                   (4 * s.spacing[a] * s.spacing[b]);
      }
    }
  }

  KEYMESH_HD void border_derivatives(Id id, const Id ijk[3], double g[3], double h[6]) const {
    const Id dims[3] = {s.nx, s.ny, s.nz};
    auto at = [&](int da, int db, int a, int b) {
      Id q = id;
      const int d[2] = {da, db};
      const int ax[2] = {a, b};
      for (int k = 0; k < 2; ++k) {
        if (d[k] == 0) continue;
        const Id c = ijk[ax[k]] + d[k];
        if (c >= 0 && c < dims[ax[k]]) q += d[k] * s.stride[ax[k]];
      }
      const double v = static_cast<double>(samples[q]);
      return std::isfinite(v) ? v : static_cast<double>(samples[id]);
    };
    const double f0 = static_cast<double>(samples[id]);
    border_gradient(id, ijk, g);
    for (int a = 0; a < 3; ++a) h[a] = (at(1, 0, a, a) - 2 * f0 + at(-1, 0, a, a)) / (s.spacing[a] * s.spacing[a]);
    const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (int k = 0; k < 3; ++k) {
      const int a = pairs[k][0], b = pairs[k][1];
      h[3 + k] = (at(1, 1, a, b) - at(1, -1, a, b) - at(-1, 1, a, b) + at(-1, -1, a, b)) /
                 (4 * s.spacing[a] * s.spacing[b]);
    }
  }

  // The grid point at the edge's far end (its first is p.p0).
  KEYMESH_HD Id far_end(const Point& p) const { return p.p0 + s.stride[p.axis]; }
  // The grid point nearest the crossing on its edge (coarsening's key,
  // paper Section 6.1): the far end from t = 0.5 on.
  KEYMESH_HD Id nearest_point(const Point& p) const { return p.t >= 0.5 ? far_end(p) : p.p0; }

  // Mean curvature at the point: (|g|^2 tr H - g^T H g) / (2 |g|^3).
  KEYMESH_HD float mean_curvature(const Point& p) const {
    double g0[3], g1[3], h0[6], h1[6];
    Id ijk1[3] = {p.ijk[0], p.ijk[1], p.ijk[2]};
    ++ijk1[p.axis];
    derivatives_at(p.p0, p.ijk, g0, h0);
    derivatives_at(far_end(p), ijk1, g1, h1);
    return mean_curvature(p, g0, h0, g1, h1);
  }

  // The same from the derivatives_at of the edge's two ends (g0, h0 at
  // p.p0, g1, h1 at far_end(p)), which the structured plan computes once
  // per grid point for all the edges that end there.
  KEYMESH_HOT_INLINE KEYMESH_HD float mean_curvature(const Point& p, const double* g0, const double* h0, const double* g1,
                                  const double* h1) const {
    double g[3], h[6];
    for (int a = 0; a < 3; ++a) g[a] = g0[a] + p.t * (g1[a] - g0[a]);
    for (int a = 0; a < 6; ++a) h[a] = h0[a] + p.t * (h1[a] - h0[a]);
    const double gg = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
    if (!(gg > 0)) return 0.f;
    const double hg[3] = {h[0] * g[0] + h[3] * g[1] + h[4] * g[2], h[3] * g[0] + h[1] * g[1] + h[5] * g[2],
                          h[4] * g[0] + h[5] * g[1] + h[2] * g[2]};
    const double ghg = g[0] * hg[0] + g[1] * hg[1] + g[2] * hg[2];
    const double k = (gg * (h[0] + h[1] + h[2]) - ghg) / (2 * gg * std::sqrt(gg));
    return std::isfinite(k) ? static_cast<float>(k) : 0.f;
  }

  // Outward unit normal: minus the interpolated gradient (values fall outward).
  KEYMESH_HD void gradient_normal(const Point& p, float* n) const {
    double g0[3], g1[3];
    Id ijk1[3] = {p.ijk[0], p.ijk[1], p.ijk[2]};
    ++ijk1[p.axis];
    gradient_at(p.p0, p.ijk, g0);
    gradient_at(far_end(p), ijk1, g1);
    gradient_normal(p, g0, g1, n);
  }

  // The same from the gradient_at of the edge's two ends (g0 at p.p0, g1
  // at far_end(p)).
  KEYMESH_HOT_INLINE KEYMESH_HD void gradient_normal(const Point& p, const double* g0, const double* g1, float* n) const {
    double g[3], len2 = 0;
    for (int a = 0; a < 3; ++a) {
      g[a] = -(g0[a] + p.t * (g1[a] - g0[a]));
      len2 += g[a] * g[a];
    }
    const double inv = len2 > 0 ? 1.0 / std::sqrt(len2) : 0.0;
    for (int a = 0; a < 3; ++a) n[a] = static_cast<float>(g[a] * inv);
  }
};

}  // namespace keymesh::generate
