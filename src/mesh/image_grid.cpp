#include "keymesh/mesh/image_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "keymesh/mesh/label_scalars.hpp"
#include "keymesh/parallel/for_each.hpp"

namespace keymesh {

std::string wide_samples_refusal(ScalarType type) {
  return std::string(scalar_type_name(type)) +
         " samples are label ids, which keymesh labels (Python: contour_labels) reads; isosurfaces and the other "
         "volume operations take uint8, int8, uint16, int16, int32, float32 or float64 (convert the volume to "
         "float64 for a contour)";
}

void check_float32_geometry(const std::array<Id, 3>& dims, const std::array<double, 3>& origin,
                            const std::array<double, 3>& spacing, const std::string& what) {
  constexpr double kMax = std::numeric_limits<float>::max();
  const char* axis = "xyz";
  auto text = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return std::string(b);
  };
  for (int a = 0; a < 3; ++a) {
    if (!(std::fabs(origin[a]) <= kMax))
      throw InputError(what + ": origin " + axis[a] + " = " + text(origin[a]) + " is not a finite float32");
    if (!(std::fabs(spacing[a]) <= kMax))
      throw InputError(what + ": spacing " + axis[a] + " = " + text(spacing[a]) + " is not a finite float32");
    // The far corner; the points between lie between it and the origin.
    const double last = origin[a] + spacing[a] * static_cast<double>(std::max<Id>(dims[a] - 1, 0));
    if (!(std::fabs(last) <= kMax))
      throw InputError(what + ": point " + std::to_string(std::max<Id>(dims[a] - 1, 0)) + " along " + axis[a] +
                       " lies at " + text(last) + " (origin " + text(origin[a]) + " + spacing " + text(spacing[a]) +
                       " x " + std::to_string(std::max<Id>(dims[a] - 1, 0)) + "), past float32's range");
  }
}

void ImageGrid::allocate_unwritten(std::array<Id, 3> new_dims, ScalarType new_type) {
  constexpr Id kMax = std::numeric_limits<Id>::max();
  Id count = 1;
  for (int a = 0; a < 3; ++a) {
    if (new_dims[a] <= 0)
      throw InputError("grid dimension " + std::to_string(a) + " is " + std::to_string(new_dims[a]) +
                       " (must be positive)");
    if (count > kMax / new_dims[a])
      throw LimitError("grid dimensions " + std::to_string(new_dims[0]) + "x" + std::to_string(new_dims[1]) +
                       "x" + std::to_string(new_dims[2]) + " overflow a 64-bit point count");
    count *= new_dims[a];
  }
  const Id size = static_cast<Id>(scalar_size(new_type));
  if (count > kMax / size / 4)
    throw LimitError("grid of " + std::to_string(count) + " points is too large");
  dims = new_dims;
  type = new_type;
  bytes.clear();  // nothing copied if the storage grows
  bytes.resize(static_cast<std::size_t>(count * size));
}

void ImageGrid::allocate(std::array<Id, 3> new_dims, ScalarType new_type) {
  allocate_unwritten(new_dims, new_type);
  std::fill(bytes.begin(), bytes.end(), std::byte{0});
}

// The samples' range, by chunks on the threads. Integer samples are
// compared as themselves (a loop the compiler vectorises: the command line
// reads a volume's range before every contour, and the per-sample double
// conversion and finiteness test cost more than the rest of the read);
// floating samples skip NaN and infinities.
std::array<double, 2> scalar_range(const ImageGrid& grid) {
  return visit_any_scalars(grid, [&](const auto* s) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(s)>>;
    constexpr double kInf = std::numeric_limits<double>::infinity();
    const Id n = grid.num_points();
    const int chunks = std::max(parallel::chunk_count(n, Id{1} << 20), 1);
    std::vector<std::array<double, 2>> part(static_cast<std::size_t>(chunks), {kInf, -kInf});
    parallel::for_each_chunk(n, chunks, [&](Id b, Id e, int c) {
      if (b == e) return;
      if constexpr (std::is_integral_v<T>) {
        T lo = s[b], hi = s[b];
        for (Id i = b; i < e; ++i) {
          const T v = s[i];
          lo = v < lo ? v : lo;
          hi = v > hi ? v : hi;
        }
        part[static_cast<std::size_t>(c)] = {static_cast<double>(lo), static_cast<double>(hi)};
      } else {
        double lo = kInf, hi = -kInf;
        for (Id i = b; i < e; ++i) {
          const double v = static_cast<double>(s[i]);
          if (!std::isfinite(v)) continue;
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
        part[static_cast<std::size_t>(c)] = {lo, hi};
      }
    });
    double lo = kInf, hi = -kInf;
    for (const auto& [l, h] : part) lo = std::min(lo, l), hi = std::max(hi, h);
    if (lo > hi) return std::array<double, 2>{0.0, 0.0};
    return std::array<double, 2>{lo, hi};
  });
}

}  // namespace keymesh
