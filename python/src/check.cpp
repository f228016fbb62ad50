// keymesh.check: the topology report of `keymesh check`.
#include "common.hpp"
#include "keymesh/analyze/topology.hpp"

namespace keymesh::python {

namespace {

py::dict check(const py::handle& mesh_obj, int threads) {
  check_threads(threads);
  const SurfaceMesh mesh = mesh_from_python(mesh_obj);
  analyze::TopologyReport t;
  {
    py::gil_scoped_release release;
    ThreadScope scope(threads);
    t = analyze::check_topology(mesh);
  }
  py::dict r;
  r["points"] = t.points;
  r["cells"] = t.cells;
  r["edges"] = t.edges;
  r["boundary_edges"] = t.boundary_edges;
  r["nonmanifold_edges"] = t.nonmanifold_edges;
  r["nonmanifold_vertices"] = t.nonmanifold_vertices;
  r["duplicate_points"] = t.duplicate_points;
  r["unused_points"] = t.unused_points;
  r["degenerate_cells"] = t.degenerate_cells;
  r["components"] = t.components;
  r["euler_characteristic"] = t.euler_characteristic;
  r["closed_manifold"] = t.closed_manifold;
  return r;
}

}  // namespace

void register_check(py::module_& m) {
  m.def("check", &check, py::arg("mesh"), py::arg("threads") = 0,
        "Topology report of a Mesh (the keys of `keymesh check --report`). Use keymesh.check.");
}

}  // namespace keymesh::python
