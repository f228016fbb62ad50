#pragma once
// Tetrahedralization of hexahedral cells (paper, Section 5.2, Table 1).
//
// Scheme 5: the minimal split of a hexahedron into 5 tetrahedra, a central
// tet on four mutually non-adjacent corners and one tet cut off at each of
// the other four corners. The two possible central tets (on the "even" or the
// "odd" corners) alternate like a checkerboard, so the face diagonals of
// neighbouring cells match and the mesh is conforming (no hanging edges).
//
// Every tet is positively oriented: det(p1 - p0, p2 - p0, p3 - p0) > 0.
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/generate/unstructured/tet_kernels.hpp"  // tet_volume
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::generate {

// A voxel grid of N = nx*ny*nz points becomes N points (same ids, x fastest)
// and 5 (nx-1)(ny-1)(nz-1) tets; voxel (i, j, k) takes the even split when
// i + j + k is even. The grid's scalars become the float point field of the
// grid's name. Throws LimitError naming the sizes when they cannot be held.
UnstructuredGrid tetrahedralize5(const ImageGrid& grid);
// tetrahedralize5(grid)'s checks alone (the same errors), for the device path.
void check_tetrahedralize5_input(const ImageGrid& grid);

// Hexahedral cells (VTK_HEXAHEDRON or VTK_VOXEL) of an unstructured grid
// become 5 tets each, points and point fields unchanged, each tet carrying its
// hexahedron's cell fields. The even/odd split of every cell is chosen so that
// the diagonals agree across every shared face (a 2-colouring of the cells
// through their faces); throws InputError naming the cells when no such
// choice exists (an odd cycle of cells) or a cell is not a hexahedron.
UnstructuredGrid tetrahedralize5(const UnstructuredGrid& hexes);

// Scheme 24, face-centred (paper, Section 5.2, Table 4): every hexahedron
// becomes 24 tets, one per (face, face edge): the edge's two corners, the
// face's centre and the cell's centre. Face-centre points are keyed by the
// face (on a voxel grid its implicit id, 3 * lower corner + normal axis, so
// KEY-REDUCE's dense plan groups them; on a hex grid the face's smallest
// corner id and the corner diagonally opposite), so the two cells sharing a
// face share its centre; cell centres are unique; corners pass through.
// Point fields are averaged over the face's 4 or the cell's 8 corners, cell
// fields copied to the children. On an N^3 grid: 24 (N-1)^3 tets and
// N^3 + 3 N (N-1)^2 + (N-1)^3 points. Every tet positively oriented.
// `vertex_weld` welds the face centres by coordinates instead (the baseline).
UnstructuredGrid tetrahedralize24(const ImageGrid& grid, bool vertex_weld = false);
// tetrahedralize24(grid)'s checks alone (the same errors), for the device path.
void check_tetrahedralize24_input(const ImageGrid& grid);
UnstructuredGrid tetrahedralize24(const UnstructuredGrid& hexes, bool vertex_weld = false);

// The points of a voxel grid (ids as in the grid, x fastest) with its
// scalars as a float point field, and no cells.
UnstructuredGrid grid_points(const ImageGrid& grid);


}  // namespace keymesh::generate
