#pragma once
// SurfaceMesh: points and polygonal cells (triangles unless offsets say
// otherwise) with named point fields, structure-of-arrays like VTK's vtkPolyData.
// The arrays are Arrays (core/array.hpp): resize(n) leaves new elements
// unwritten, so a generator writes its output once.
#include <cstdint>
#include <string>
#include <vector>

#include "keymesh/core/array.hpp"
#include "keymesh/core/types.hpp"

namespace keymesh {

// A named array of `components` floats per element.
struct Field {
  std::string name;
  int components = 1;
  Array<float> values;
};

// The field named `name` in `fields`, or null.
inline const Field* find_field(const std::vector<Field>& fields, const std::string& name) {
  for (const auto& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}

struct SurfaceMesh {
  Array<float> points;                 // x,y,z per point
  Array<PointIndex> connectivity;      // point ids of every cell, cell after cell
  // Cell c spans connectivity[offsets[c], offsets[c+1]). Empty means every
  // cell is a triangle (the common case: no offsets array is stored).
  Array<std::uint64_t> offsets;
  std::vector<Field> point_fields;
  // One tuple per cell (e.g. a label map's boundary_labels). Written by the
  // .vtp writer as CellData; the other formats have no place for them.
  std::vector<Field> cell_fields;

  Id num_points() const { return static_cast<Id>(points.size() / 3); }
  Id num_cells() const {
    return offsets.empty() ? static_cast<Id>(connectivity.size() / 3)
                           : static_cast<Id>(offsets.size()) - 1;
  }
  bool all_triangles() const { return offsets.empty(); }
  std::uint64_t cell_begin(Id c) const { return offsets.empty() ? 3 * std::uint64_t(c) : offsets[c]; }
  std::uint64_t cell_end(Id c) const { return offsets.empty() ? 3 * std::uint64_t(c) + 3 : offsets[c + 1]; }

  const Field* find_point_field(const std::string& name) const { return find_field(point_fields, name); }
  const Field* find_cell_field(const std::string& name) const { return find_field(cell_fields, name); }
};

}  // namespace keymesh
