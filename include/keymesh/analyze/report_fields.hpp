#pragma once
// The analyses' reports as (name, value) pairs, one list each, so that
// `keymesh check --report` and keymesh.check(), `keymesh quality --report`
// and keymesh.quality() name the same numbers the same way.
//
//   visit_fields(report, [&](const char* name, const auto& value) { json[name] = value; });
#include "keymesh/analyze/quality.hpp"
#include "keymesh/analyze/topology.hpp"

namespace keymesh::analyze {

template <class Visit>
void visit_fields(const TopologyReport& t, Visit&& visit) {
  visit("points", t.points);
  visit("cells", t.cells);
  visit("edges", t.edges);
  visit("boundary_edges", t.boundary_edges);
  visit("nonmanifold_edges", t.nonmanifold_edges);
  visit("nonmanifold_vertices", t.nonmanifold_vertices);
  visit("duplicate_points", t.duplicate_points);
  visit("unused_points", t.unused_points);
  visit("degenerate_cells", t.degenerate_cells);
  visit("components", t.components);
  visit("euler_characteristic", t.euler_characteristic);
  visit("closed_manifold", t.closed_manifold);
}

// "cells" is the triangle count; the mesh's point count is the caller's.
template <class Visit>
void visit_fields(const QualityReport& q, Visit&& visit) {
  visit("cells", q.triangles);
  visit("min", q.min);
  visit("median", q.median);
  visit("mean", q.mean);
  visit("fraction_above_0_6", q.fraction_above_0_6);
  visit("histogram", q.histogram);
}

}  // namespace keymesh::analyze
