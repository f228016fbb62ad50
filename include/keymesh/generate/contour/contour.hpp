#pragma once
// Marching cubes on a uniform voxel grid, welded by history (paper, Section 4.2).
//
// Every triangle corner is keyed by the implicit id of the grid edge it lies
// on, 3 * point_id + axis (plus iso_index * 3 * N when several isovalues are
// contoured at once). KEY-REDUCE groups the corners by key; by default with
// its structured plan, which numbers the cut edges by counting them per grid
// row (no sort, no soup: src/generate/contour/contour_rows.hpp), so triangles are
// written with their final point ids, and every point's position and fields
// are computed once per unique edge from the edge's two samples.
//
// Guarantees:
//  - inside means value >= iso; NaN samples are outside. A point is created
//    for every grid edge whose end samples straddle the isovalue, and only
//    those (the same count as VTK's marching cubes and flying edges); no two
//    output points share a key.
//  - triangles come from a consistent case table (see marching_cubes_table.hpp):
//    a closed isosurface inside the grid is a closed 2-manifold, triangles
//    wound so that their normals point to lower values (outside).
//  - output is bit-identical for any thread count.
//  - ContourWeld::VertexWeld welds the same triangle soup by coordinates instead
//    (the paper's baseline); its mesh equals the KEY-REDUCE mesh up to point order.
#include <functional>
#include <string>
#include <vector>

#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/surface_mesh.hpp"

namespace keymesh::generate {

enum class ContourNormals { None, Gradient, Average };
// How the corners of the triangle soup become connected points:
//  - KeyReduce:     KEY-REDUCE, structured plan: the cut edges are counted per
//                   grid row and numbered by prefix sums, so no soup is written
//                   and nothing is sorted (default);
//  - KeyReduceSort: KEY-REDUCE, sort plan (radix sort of the significant key bits);
//  - VertexWeld:    the soup of positions, welded by coordinates (the baseline).
// All three give the same mesh; the two KEY-REDUCE plans the same point order.
enum class ContourWeld { KeyReduce, KeyReduceSort, VertexWeld };
// Where the contour runs: CPU threads, or an NVIDIA GPU (keymesh/cuda/backend.hpp:
// byte-identical output; what the GPU does not support yet is refused by name).
// The choice is made by keymesh/backend/contour.hpp, above generate.
enum class Backend { Cpu, Cuda };

// Output arrays a caller owns (ContourOptions::output_arrays): 3 floats per
// point, 3 ids per triangle, and one float per point when scalars are on.
struct ContourArrays {
  float* points = nullptr;
  PointIndex* connectivity = nullptr;
  float* scalars = nullptr;
};

struct ContourOptions {
  std::vector<double> isovalues;        // at least one, all finite
  Backend backend = Backend::Cpu;
  ContourNormals normals = ContourNormals::None;
  ContourWeld weld = ContourWeld::KeyReduce;
  bool scalars = true;                  // carry the interpolated input scalar as a point field
  // Coarsening (paper, Section 6.1): the key of a crossing becomes the input
  // point nearest to it on its edge; points sharing one are merged (positions
  // and fields averaged) and triangles left with fewer than three distinct
  // points are dropped. Averaged normals are computed after the merge.
  bool coarsen = false;
  // Mean curvature per point from the volume's gradient g and Hessian H
  // (central differences, interpolated along the edge; Kindlmann et al.
  // 2003): kappa = (|g|^2 tr(H) - g^T H g) / (2 |g|^3), half the divergence
  // of g / |g|. For the Spherical Distance field (values growing outward)
  // a sphere of radius r has kappa = 1/r. Point field "mean_curvature".
  // Voxel grids only.
  bool curvature = false;
  // Per-point history (docs/HISTORY.md): point field "history_t", the float
  // t in [0, 1] along the point's edge (its key, through contour()'s
  // point_keys, is history_key) from the edge's lower grid point, chosen
  // among the floats next to the crossing's t so that
  //   x[axis] = float(origin[axis] + spacing[axis] * (double(c) + double(t)))
  // (c the lower end's index along the axis, in the whole grid) gives the
  // written coordinate bit for bit where such a float exists (see
  // history_t.hpp for the bound elsewhere). Not with coarsening (a coarse
  // point has no one edge) nor output_arrays (InputError).
  bool history = false;
  // The grid's axes are the caller's in reverse order (x <-> z: a C-order
  // numpy array seen without a copy, the output mirrored back by the
  // caller): cubes are split by the mirrored table (coarsening's tables are
  // built from it), so the caller gets the triangles of its own frame.
  bool reversed_axes = false;
  // Voxel grids: when the grid is planes [first_plane, first_plane + nz) of
  // a grid of total_planes planes (0: not a slab), positions use the global
  // plane index and the keys returned through contour()'s point_keys are
  // global edge ids of the whole grid (see contour_stream.hpp).
  Id first_plane = 0;
  Id total_planes = 0;
  // Voxel grids: the grid is a box of a larger grid whose first grid point
  // is the larger grid's point (position_offset[0], [1], [2]): positions
  // are computed from the larger grid's indices, the same bits as there.
  // Keys stay the box's own (a Dask block, python/src/dask_contour.cpp,
  // renumbers them); derivatives see the box's borders as the grid's.
  Id position_offset[3] = {0, 0, 0};
  // Slabs only: the grid's first `ghost_below` and last `ghost_above` planes
  // (0 or 1 each) are ghosts: samples the derivatives need (gradient
  // normals, curvature: central differences across the slab's border), in
  // no generated cell. A slab with ghosts gives the bits of the whole grid.
  Id ghost_below = 0;
  Id ghost_above = 0;
  // Voxel grids: the most bytes the output (points, fields, triangles) may
  // take (0: no bound). Checked once the rows are counted, before any output
  // is allocated: a contour past it is refused by name (LimitError) instead
  // of running into the OOM killer.
  std::uint64_t max_output_bytes = 0;
  // Unstructured grids only: the point field to contour (empty: the first
  // one-component point field). Every point field is carried, interpolated.
  std::string array;
  // Voxel grids, structured plan (weld KeyReduce) with no normals, no
  // curvature and no coarsening: when set, called once the rows are
  // counted, with the output's point and triangle counts, for the arrays
  // to write the points, triangles and scalars into (in place, each
  // element once); the mesh returned then holds none of them. For a host
  // that hands the output over as it is (the Python module): arrays it
  // allocates, each element written once (as the mesh's own Arrays are,
  // core/array.hpp, since they are sized without a zero fill). Other
  // options with it are refused (InputError).
  std::function<ContourArrays(Id points, Id triangles)> output_arrays;
};

// Where the time went, in seconds, and the sizes involved.
struct ContourStats {
  double classify = 0;    // inside/outside bits and per-row triangle counts
  double generate = 0;    // triangle soup: an edge key per corner
  double weld = 0;        // KEY-REDUCE partition (or VERTEX-WELD), with the pair order when averaging
  double fields = 0;      // positions, scalars, normals per unique point
  double coarsen = 0;     // merging by nearest grid point (with --coarsen)
  Id triangles_before_coarsening = 0;
  Id soup_points = 0;     // triangle corners (pairs) before welding
  int key_bits = 0;       // width of the keys used (32 or 64)
  // --backend cuda: the high-water mark of the device memory pool during the
  // contour (samples, soup, sort buffers, mesh), in bytes; 0 on the CPU.
  std::uint64_t device_peak_bytes = 0;
};

// Throws InputError for an empty isovalue list, a non-finite isovalue, a
// grid with fewer than 2 points along an axis or fewer bytes than its dims
// need: the input checks of contour() on voxels, whichever backend runs it.
void check_contour_input(const ImageGrid& grid, const ContourOptions& options);

// Throws LimitError when an output of `points` points and `triangles`
// triangles passes options.max_output_bytes or 2^32 - 1 corners: the check
// contour() makes before it allocates its output, for the GPU path to make
// with its own counts (the same message).
void check_contour_output(const ContourOptions& options, Id points, Id triangles);

// Runs on the CPU: options.backend must be Backend::Cpu (keymesh/backend/contour.hpp
// chooses between the CPU and the GPU).
// Throws InputError for an empty isovalue list, a non-finite isovalue or a
// grid with fewer than 2 points along an axis; LimitError when the output
// would exceed 2^32 - 1 points or triangle corners.
// point_keys, when given, receives every output point's key: its grid edge,
// 3 * point id + axis + iso_index * 3N (N the points of the whole grid).
// nearest_keys, when given, receives every output point's coarse key: the
// grid point of the whole grid nearest to it on its edge, + iso_index * N.
// A caller that merges slabs by point_keys coarsens the merged mesh with
// these (coarsen()); options.coarsen must then be off (InputError).
SurfaceMesh contour(const ImageGrid& grid, const ContourOptions& options, ContourStats* stats = nullptr,
                    std::vector<std::uint64_t>* point_keys = nullptr,
                    std::vector<std::uint64_t>* nearest_keys = nullptr);

// Voxel grids: the triangles marching cubes makes in each voxel layer
// (layer k between planes k and k + 1), summed over the isovalues, from the
// classification pass alone (no soup, no weld): what a distributed run
// balances its slabs by.
std::vector<Id> triangles_per_layer(const ImageGrid& grid, const ContourOptions& options);

}  // namespace keymesh::generate
