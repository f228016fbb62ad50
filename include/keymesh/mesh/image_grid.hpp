#pragma once
// ImageGrid: a uniform voxel grid (VTK's vtkImageData), one scalar per point,
// x varying fastest. The scalar array keeps its native type; algorithms
// dispatch on it with visit_scalars().
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "keymesh/core/array.hpp"
#include "keymesh/core/error.hpp"
#include "keymesh/core/types.hpp"
#include "keymesh/mesh/scalar_type.hpp"

namespace keymesh {

struct ImageGrid {
  std::array<Id, 3> dims{0, 0, 0};           // number of points along x, y, z
  std::array<double, 3> origin{0.0, 0.0, 0.0};
  std::array<double, 3> spacing{1.0, 1.0, 1.0};
  ScalarType type = ScalarType::Float32;
  std::string name = "scalars";              // the point field's name
  Array<std::byte> bytes;                    // dims[0]*dims[1]*dims[2] samples, native endian (no zero fill:
                                             // a reader writes every sample)
  // A non-owning view instead of `bytes` (e.g. a numpy array's memory, which
  // must outlive every use of the grid): when set, algorithms read the
  // samples from here and `bytes` stays empty.
  const std::byte* external = nullptr;

  Id num_points() const { return dims[0] * dims[1] * dims[2]; }
  const void* data() const { return external ? static_cast<const void*>(external) : bytes.data(); }
  void* data() { return bytes.data(); }  // the owned samples (writers, readers)
  // Bytes of samples the grid holds (owned or viewed).
  std::size_t byte_count() const {
    return external ? static_cast<std::size_t>(num_points()) * scalar_size(type) : bytes.size();
  }

  // Allocates bytes for dims and type after checking every product for
  // overflow; throws LimitError naming the dims otherwise. The samples are
  // zeros.
  void allocate(std::array<Id, 3> new_dims, ScalarType new_type);
  // The same with the samples left unwritten, for a reader that writes every
  // one (no zero fill of the whole volume first).
  void allocate_unwritten(std::array<Id, 3> new_dims, ScalarType new_type);
};

// Calls f(const T* samples) with T the grid's C++ sample type.
template <class F>
decltype(auto) visit_scalars(const ImageGrid& grid, F&& f) {
  switch (grid.type) {
    case ScalarType::UInt8: return f(reinterpret_cast<const std::uint8_t*>(grid.data()));
    case ScalarType::Int8: return f(reinterpret_cast<const std::int8_t*>(grid.data()));
    case ScalarType::UInt16: return f(reinterpret_cast<const std::uint16_t*>(grid.data()));
    case ScalarType::Int16: return f(reinterpret_cast<const std::int16_t*>(grid.data()));
    case ScalarType::Int32: return f(reinterpret_cast<const std::int32_t*>(grid.data()));
    case ScalarType::Float32: return f(reinterpret_cast<const float*>(grid.data()));
    case ScalarType::Float64: return f(reinterpret_cast<const double*>(grid.data()));
    case ScalarType::UInt32:
    case ScalarType::Int64:
    case ScalarType::UInt64: break;  // not a grid type (is_grid_scalar): every reader refuses it
  }
  throw InputError(std::string("a grid of ") + scalar_type_name(grid.type) + " samples is not supported");
}

// Throws InputError "<what>: ..." unless the origin and every grid point
// origin + spacing * i (0 <= i < dims) have coordinates that are finite in
// float32, the type every mesh stores its points in: an origin of 1e39 or a
// spacing of 1e38 would otherwise give a mesh of inf coordinates.
void check_float32_geometry(const std::array<Id, 3>& dims, const std::array<double, 3>& origin,
                            const std::array<double, 3>& spacing, const std::string& what);

// Minimum and maximum of the finite samples (NaN and Inf skipped); {0,0} when
// there are none.
std::array<double, 2> scalar_range(const ImageGrid& grid);

}  // namespace keymesh
