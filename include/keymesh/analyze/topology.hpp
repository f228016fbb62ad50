#pragma once
// Topology check of a polygon surface: is it a closed 2-manifold?
#include <span>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::analyze {

struct TopologyReport {
  Id points = 0;               // points in the mesh
  Id cells = 0;                // polygons
  Id edges = 0;                // distinct undirected edges
  Id boundary_edges = 0;       // edges used by exactly one cell
  Id nonmanifold_edges = 0;    // edges used by three or more cells
  Id nonmanifold_vertices = 0; // vertices whose incident cells do not form a single fan/disk
  Id duplicate_points = 0;     // points whose position equals an earlier point's exactly
  Id unused_points = 0;        // points no cell refers to
  Id degenerate_cells = 0;     // cells that repeat a point id
  Id components = 0;           // connected components of cells (through shared points)
  Id euler_characteristic = 0; // V - E + F over used points
  bool closed_manifold = false;// no boundary, no non-manifold edge or vertex, no degenerate cell
};

// Deterministic, threaded where it pays. Throws InputError when a cell refers
// to a point id out of range or the offsets are malformed, LimitError past
// 2^32 - 1 points, cells or corners. Cells with fewer than three ids count as
// degenerate; an edge from a point to itself (inside a degenerate cell) is
// not an edge. Duplicate points compare positions with float == (so -0 == +0
// and NaN never matches).
TopologyReport check_topology(const SurfaceMesh& mesh);

// The edge and vertex counts of check_topology alone (points, cells, edges,
// boundary, non-manifold edges and vertices, unused points, degenerate
// cells), without the duplicate positions, components and Euler
// characteristic (left 0) and closed_manifold (left false): what a
// coarsened contour's report needs, at about three quarters of the cost.
TopologyReport check_fans(const SurfaceMesh& mesh);
// The same counted at the marked points only (counted[v] != 0, one mark a
// point): their vertices, and the edges whose smaller end they are; a part
// of a mesh that holds every cell at its marked points counts their share.
TopologyReport check_fans(const SurfaceMesh& mesh, std::span<const std::uint8_t> counted);

namespace detail {
// check_topology's duplicate_points of the n points at xyz; `hash_bits` (1 to
// 32) sets how many bits of the positions' hash group them (0: as many as n
// needs), so that a test can make every run hold many positions.
Id count_duplicate_points(const float* xyz, Id n, int hash_bits = 0);
}  // namespace detail

}  // namespace keymesh::analyze
