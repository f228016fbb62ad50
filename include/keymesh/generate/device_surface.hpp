#pragma once
// A triangle mesh in a device's memory (the generators' device paths:
// subdivision, coarsening), and its way there and back. The arrays are the
// device's (D::Array); on the CPU device they are host memory and move into
// the mesh without a copy.
#include <string>
#include <utility>
#include <vector>

#include "keymesh/core/types.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::generate::device_surface {

template <class D>
struct Field {
  std::string name;
  int components = 1;
  typename D::template Array<float> values;
};

template <class D>
struct Surface {
  typename D::template Array<float> points;
  typename D::template Array<PointIndex> triangles;
  std::vector<Field<D>> point_fields, cell_fields;
  Id points_count = 0, triangle_count = 0;
};

template <class D>
Surface<D> upload(const D& d, const SurfaceMesh& m) {
  Surface<D> s{d.upload(m.points.data(), static_cast<Id>(m.points.size())),
               d.upload(m.connectivity.data(), static_cast<Id>(m.connectivity.size())), {}, {}, m.num_points(),
               m.num_cells()};
  for (const keymesh::Field& f : m.point_fields)
    s.point_fields.push_back({f.name, f.components, d.upload(f.values.data(), static_cast<Id>(f.values.size()))});
  for (const keymesh::Field& f : m.cell_fields)
    s.cell_fields.push_back({f.name, f.components, d.upload(f.values.data(), static_cast<Id>(f.values.size()))});
  return s;
}

template <class D>
SurfaceMesh download(const D& d, Surface<D>&& s) {
  SurfaceMesh m;
  m.points = d.to_host(std::move(s.points));
  m.connectivity = d.to_host(std::move(s.triangles));
  for (Field<D>& f : s.point_fields) m.point_fields.push_back({f.name, f.components, d.to_host(std::move(f.values))});
  for (Field<D>& f : s.cell_fields) m.cell_fields.push_back({f.name, f.components, d.to_host(std::move(f.values))});
  return m;
}

}  // namespace keymesh::generate::device_surface
