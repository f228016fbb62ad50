#pragma once
// The generators' statistics as (name, value) pairs, one list each, so that
// the commands' --report and the Python functions' stats and info dicts name
// the same numbers the same way (as analyze/report_fields.hpp does for the
// analyses).
//
//   visit_fields(dual_stats, [&](const char* name, const auto& value) { json[name] = value; });
#include <utility>

#include "keymesh/generate/coarsen/coarsen.hpp"
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/unstructured/dual.hpp"
#include "keymesh/generate/labels/labels.hpp"

namespace keymesh::generate {

// The fans the dual could not close (keymesh dual --report, keymesh.dual).
template <class Visit>
void visit_fields(const DualStats& s, Visit&& visit) {
  visit("boundary_fans", s.boundary_fans);
  visit("nonmanifold_points", s.nonmanifold_points);
  visit("skipped_fans", s.skipped_fans);
}

// Counts before and after coarsening an existing mesh (keymesh.coarsen).
template <class Visit>
void visit_fields(const CoarsenStats& s, Visit&& visit) {
  const std::pair<const char*, Id> counts[] = {{"points_before", s.points_before},
                                               {"points_after", s.points_after},
                                               {"triangles_before", s.triangles_before},
                                               {"triangles_after", s.triangles_after},
                                               {"folded", s.folded}};
  for (const auto& [name, count] : counts) visit(name, count);
}

// Seconds of the contour's steps (keymesh contour --report's
// "contour_stages", keymesh.contour's info).
template <class Visit>
void visit_stage_seconds(const ContourStats& s, Visit&& visit) {
  const std::pair<const char*, double> stages[] = {
      {"classify", s.classify}, {"generate", s.generate}, {"weld", s.weld}, {"fields", s.fields},
      {"coarsen", s.coarsen}};
  for (const auto& [name, seconds] : stages) visit(name, seconds);
}

// Seconds of the label generator's steps (keymesh labels --report's
// "labels_stages", keymesh.contour_labels' info).
template <class Visit>
void visit_stage_seconds(const LabelStats& s, Visit&& visit) {
  const std::pair<const char*, double> stages[] = {{"scan", s.scan}, {"generate", s.generate}, {"weld", s.weld},
                                                   {"smooth", s.smooth}, {"coarsen", s.coarsen}};
  for (const auto& [name, seconds] : stages) visit(name, seconds);
}

}  // namespace keymesh::generate
