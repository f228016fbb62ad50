#pragma once
// UnstructuredGrid: points, cells of VTK cell types, point and cell fields,
// structure-of-arrays like VTK's vtkUnstructuredGrid.
//
// Point ids are stored 32-bit while the point count fits in 32 bits and
// 64-bit beyond (IndexArray picks the width at run time), so a grid of
// 82,906,875 tets (256^3, scheme 5) costs 4 bytes per corner, and grids past
// 2^32 points still work instead of overflowing.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "keymesh/core/types.hpp"
#include "keymesh/mesh/surface_mesh.hpp"  // Field

namespace keymesh {

// VTK's cell type codes (vtkCellType.h), so files round-trip unchanged.
enum class CellType : std::uint8_t {
  Vertex = 1,
  Line = 3,
  Triangle = 5,
  Polygon = 7,
  Quad = 9,
  Tetra = 10,
  Voxel = 11,  // VTK's axis-aligned hexahedron with "pixel" corner order
  Hexahedron = 12,
  Wedge = 13,
  Pyramid = 14,
};

// Number of corners of a fixed-size cell type; 0 for Polygon (variable).
int cell_type_size(CellType t);
// "tetra", "hexahedron", ... for messages; "type N" when unknown.
std::string cell_type_name(std::uint8_t vtk_type);

// Point ids of every cell, 32-bit or 64-bit chosen at run time.
class IndexArray {
 public:
  IndexArray() = default;
  // An array of n ids wide enough to hold ids < max_id_exclusive, unwritten:
  // the caller sets every one. (An output array: huge pages asked for, first
  // touch shared by the threads, no zero fill; core/array.hpp.)
  static IndexArray for_ids(std::uint64_t max_id_exclusive, std::size_t n);
  bool wide() const { return wide_; }
  std::size_t size() const { return wide_ ? v64_.size() : v32_.size(); }
  bool empty() const { return size() == 0; }
  std::uint64_t operator[](std::size_t i) const { return wide_ ? v64_[i] : v32_[i]; }
  void set(std::size_t i, std::uint64_t v) {
    if (wide_) v64_[i] = v;
    else v32_[i] = static_cast<std::uint32_t>(v);
  }
  // Direct access to the storage of the chosen width.
  Array<std::uint32_t>& narrow() { return v32_; }
  const Array<std::uint32_t>& narrow() const { return v32_; }
  Array<std::uint64_t>& wide_values() { return v64_; }
  const Array<std::uint64_t>& wide_values() const { return v64_; }
  // Calls f(std::span<const T>) with T = uint32_t or uint64_t.
  template <class F>
  decltype(auto) visit(F&& f) const {
    return wide_ ? f(std::span<const std::uint64_t>(v64_)) : f(std::span<const std::uint32_t>(v32_));
  }
  template <class F>
  decltype(auto) visit_mut(F&& f) {
    return wide_ ? f(std::span<std::uint64_t>(v64_)) : f(std::span<std::uint32_t>(v32_));
  }

 private:
  bool wide_ = false;
  Array<std::uint32_t> v32_;
  Array<std::uint64_t> v64_;
};

struct UnstructuredGrid {
  Array<float> points;        // x,y,z per point
  IndexArray connectivity;    // corner point ids, cell after cell
  // Cell c spans connectivity[offsets[c], offsets[c+1]). Empty means every
  // cell has `uniform_type` and cell_type_size(uniform_type) corners (the
  // common all-tets case stores no offsets and no types).
  std::vector<std::uint64_t> offsets;
  // VTK type code per cell; empty means every cell is `uniform_type`.
  std::vector<std::uint8_t> cell_types;
  CellType uniform_type = CellType::Tetra;
  std::vector<Field> point_fields;
  std::vector<Field> cell_fields;

  Id num_points() const { return static_cast<Id>(points.size() / 3); }
  Id num_cells() const {
    if (!offsets.empty()) return static_cast<Id>(offsets.size()) - 1;
    return static_cast<Id>(connectivity.size() / static_cast<std::size_t>(cell_type_size(uniform_type)));
  }
  bool uniform() const { return offsets.empty(); }
  std::uint8_t cell_type(Id c) const {
    return cell_types.empty() ? static_cast<std::uint8_t>(uniform_type) : cell_types[c];
  }
  std::uint64_t cell_begin(Id c) const {
    return offsets.empty() ? std::uint64_t(c) * cell_type_size(uniform_type) : offsets[c];
  }
  std::uint64_t cell_end(Id c) const {
    return offsets.empty() ? std::uint64_t(c + 1) * cell_type_size(uniform_type) : offsets[c + 1];
  }
  // True when every cell is of type t (stored uniformly or listed).
  bool all_cells_are(CellType t) const;

  const Field* find_point_field(const std::string& name) const { return find_field(point_fields, name); }
  const Field* find_cell_field(const std::string& name) const { return find_field(cell_fields, name); }

  // Checks the structural invariants (offsets monotone and in range, ids <
  // num_points, sizes of types/fields consistent, fixed-size cells have the
  // right corner count); throws InputError naming `what` and the fault.
  // check_ids = false skips the id range check (a full read of the
  // connectivity), for callers that check each id as they read it anyway.
  void validate(const std::string& what, bool check_ids = true) const;
};

}  // namespace keymesh
