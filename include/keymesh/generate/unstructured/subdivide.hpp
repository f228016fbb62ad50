#pragma once
// Uniform subdivision keyed by the parent edge (paper, Section 5.1, Table 3).
//
// Triangles 1 -> 4 and tetrahedra 1 -> 8. Old points pass through unchanged
// (same ids); every new point is the point of one parent edge, keyed by the
// edge's two point ids, smaller first, so the triangles or tets on either
// side of an edge share it: KEY-REDUCE (sort plan) numbers the edges, its
// index map rewrites the cells, and each new point's position and fields are
// computed once from its key. New points follow the old ones in key order.
//
// Positions: `Linear` puts the new point at the edge midpoint; `Bezier`
// (triangles only) at the midpoint of the edge's cubic of a PN triangle
// (Vlachos et al. 2001), built from the two end points and their normals, so
// a subdivided sphere stays round and neighbouring triangles still agree.
// Point fields are averaged over the edge ("Normals" renormalised; with
// Bezier, the PN quadratic normal). Tet cell fields are copied to the children.
#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::generate {

enum class SubdivideScheme { Linear, Bezier };
enum class SubdivideWeld { KeyReduce, VertexWeld };

struct SubdivideOptions {
  int levels = 1;
  SubdivideScheme scheme = SubdivideScheme::Linear;
  SubdivideWeld weld = SubdivideWeld::KeyReduce;  // VertexWeld: the baseline, same mesh up to renumbering
};

// Throws InputError for polygons that are not triangles, Bezier without a
// 3-component "Normals" point field, or levels < 0; LimitError past 2^32 - 1
// points or corners.
SurfaceMesh subdivide(const SurfaceMesh& mesh, const SubdivideOptions& options);

// subdivide()'s input checks alone (the same InputError), for the device path.
void check_subdivide_input(const SurfaceMesh& mesh, const SubdivideOptions& options);

// Tetrahedra 1 -> 8: the four corner tets and the inner octahedron cut along
// its shortest diagonal; every child positively oriented. Linear only.
UnstructuredGrid subdivide(const UnstructuredGrid& tets, const SubdivideOptions& options);

// subdivide(tets)'s input checks alone (the same InputError), for the device path.
void check_subdivide_input(const UnstructuredGrid& tets, const SubdivideOptions& options);

// subdivide()'s output for --levels 0, shared by the host and device paths:
// the input, its cells in the output's layout (uniform triangles, resp.
// uniform tetrahedra).
SurfaceMesh subdivided_zero_levels(const SurfaceMesh& mesh);
UnstructuredGrid subdivided_zero_levels(const UnstructuredGrid& tets);

}  // namespace keymesh::generate
