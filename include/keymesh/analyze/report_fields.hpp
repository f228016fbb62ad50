#pragma once
// The analyses' reports as (name, value) pairs, one list each, so that
// `keymesh check --report` and keymesh.check(), `keymesh quality --report`
// and keymesh.quality() name the same numbers the same way.
//
//   visit_fields(report, [&](const char* name, const auto& value) { json[name] = value; });
#include <utility>

#include "keymesh/analyze/quality.hpp"
#include "keymesh/analyze/self_intersections.hpp"
#include "keymesh/analyze/topology.hpp"

namespace keymesh::analyze {

// The counts in the order `keymesh check` prints them, then closed_manifold.
template <class Visit>
void visit_fields(const TopologyReport& t, Visit&& visit) {
  const std::pair<const char*, Id> counts[] = {
      {"points", t.points}, {"cells", t.cells}, {"edges", t.edges}, {"boundary_edges", t.boundary_edges},
      {"nonmanifold_edges", t.nonmanifold_edges}, {"nonmanifold_vertices", t.nonmanifold_vertices},
      {"duplicate_points", t.duplicate_points}, {"unused_points", t.unused_points},
      {"degenerate_cells", t.degenerate_cells}, {"components", t.components},
      {"euler_characteristic", t.euler_characteristic}};
  for (const auto& [name, count] : counts) visit(name, count);
  visit("closed_manifold", t.closed_manifold);
}

// `keymesh check --self-intersections`: the count of crossing cell pairs,
// the first pairs (cell ids) and the zero-area triangles left out.
template <class Visit>
void visit_fields(const SelfIntersectionReport& s, Visit&& visit) {
  visit("self_intersections", s.self_intersections);
  visit("self_intersecting_pairs", s.pairs);
  visit("zero_area_triangles", s.zero_area_triangles);
}

// "cells" is the triangle count; the mesh's point count is the caller's.
template <class Visit>
void visit_fields(const QualityReport& q, Visit&& visit) {
  visit("cells", q.triangles);
  const std::pair<const char*, double> measures[] = {
      {"min", q.min}, {"median", q.median}, {"mean", q.mean}, {"fraction_above_0_6", q.fraction_above_0_6}};
  for (const auto& [name, measure] : measures) visit(name, measure);
  visit("histogram", q.histogram);
}

}  // namespace keymesh::analyze
