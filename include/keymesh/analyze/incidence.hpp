#pragma once
// Incidence lists built by KEY-REDUCE (paper, Section 6.2): the cells around
// each point are the groups of the corner pairs keyed by point id (dense
// plan; counts and offsets are the groups', the order lists their corners),
// and the neighbours of a cell across its edges are the groups of the edge
// pairs keyed by (min id, max id) (sort plan).
#include <cstdint>
#include <vector>

#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::analyze {

// Point p's incident corners are corners[offsets[p] .. offsets[p+1]), in
// increasing corner index; cell_of(corner) is the cell of a corner (a
// position in the connectivity). Only meshes with cells other than
// triangles store cell_of_corner; a triangle's corner k is in cell k / 3
// (not storing it keeps 4 bytes per corner out of the dual's peak memory).
struct PointCells {
  std::vector<Id> offsets;                 // num_points + 1
  std::vector<std::uint32_t> corners;      // connectivity positions
  std::vector<std::uint32_t> cell_of_corner;  // empty when every cell is a triangle
  Id count(Id p) const { return offsets[p + 1] - offsets[p]; }
  std::uint32_t cell_of(std::uint32_t corner) const {
    return cell_of_corner.empty() ? corner / 3 : cell_of_corner[corner];
  }
};
PointCells point_cells(const SurfaceMesh& mesh);

// What point_cells and cell_neighbours refuse: more than 2^32 - 1 corners
// (LimitError), a point id out of range (InputError).
void check_ids(const SurfaceMesh& mesh);

// For every corner k of every cell (the edge from corner k to the next
// corner), the other cell across that edge: -1 on the boundary, -2 when the
// edge is shared by more than two cells.
std::vector<std::int64_t> cell_neighbours(const SurfaceMesh& mesh);

}  // namespace keymesh::analyze
