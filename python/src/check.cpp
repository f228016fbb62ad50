// keymesh.check: the topology report of `keymesh check`.
#include "common.hpp"
#include "keymesh/analyze/report_fields.hpp"

namespace keymesh::python {

namespace {

py::dict check(const py::handle& mesh_obj, int threads, bool self_intersections) {
  check_threads(threads);
  const SurfaceMesh mesh = mesh_from_python(mesh_obj);
  const analyze::TopologyReport t = run_released(threads, [&] { return analyze::check_topology(mesh); });
  py::dict r;
  analyze::visit_fields(t, into(r));
  if (self_intersections) {
    const analyze::SelfIntersectionReport s =
        run_released(threads, [&] { return analyze::find_self_intersections(mesh); });
    analyze::visit_fields(s, into(r));
  }
  return r;
}

}  // namespace

void register_check(py::module_& m) {
  m.def("check", &check, py::arg("mesh"), py::arg("threads") = 0, py::arg("self_intersections") = false,
        "Topology report of a Mesh (the keys of `keymesh check --report`). Use keymesh.check.");
}

}  // namespace keymesh::python
