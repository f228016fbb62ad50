#pragma once
// The wide integer sample types of label maps: uint32, int64 and uint64
// (connectomics segmentations, Neuroglancer's uint64 segment ids). The
// volume readers give an ImageGrid of them; only what reads label maps
// dispatches on them (visit_any_scalars: the label scan, a volume's range,
// sample conversions in readers). Every algorithm keeps visit_scalars over
// the seven grid types (is_grid_scalar), which refuses them: another type
// there would be another instantiation of every algorithm
// (docs/decisions/wide-label-types.md).
#include <cstdint>
#include <string>
#include <utility>

#include "keymesh/mesh/image_grid.hpp"

namespace keymesh {

// True for the integer types a label map may hold: the grid's integers and
// uint32, int64, uint64.
inline bool is_label_scalar(ScalarType type) { return !scalar_is_float(type); }

// "uint64 samples are label ids, which keymesh labels ... reads; ...": why
// an algorithm over the grid types refuses a wide label type.
std::string wide_samples_refusal(ScalarType type);

// visit_scalars over every type, the wide label types too.
template <class F>
decltype(auto) visit_any_scalars(const ImageGrid& grid, F&& f) {
  switch (grid.type) {
    case ScalarType::UInt32: return f(reinterpret_cast<const std::uint32_t*>(grid.data()));
    case ScalarType::Int64: return f(reinterpret_cast<const std::int64_t*>(grid.data()));
    case ScalarType::UInt64: return f(reinterpret_cast<const std::uint64_t*>(grid.data()));
    default: return visit_scalars(grid, std::forward<F>(f));
  }
}

}  // namespace keymesh
