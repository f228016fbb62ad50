#pragma once
// The unstructured generators on an NVIDIA GPU: marching tetrahedra,
// subdivision (triangles 1 -> 4, tets 1 -> 8) and the 5- and 24-tet
// tetrahedralizations of a voxel grid. Each runs its device path
// (keymesh/generate/unstructured/*_device.hpp, the code ctest runs bit for
// bit against the CPU on the CPU device) on the CUDA device
// (src/cuda/<name>_cuda.cu), host data in and out; the output is the CPU's,
// bit for bit.
//
// Each runs its generator's input checks first (the CPU's InputError), then
// refuses by name what its device path lacks (VERTEX-WELD, coarsening), then
// InputError "--backend cuda: <why> (use --backend cpu)" when no usable device
// is present or keymesh was built without CUDA (src/cuda/backend_stub.cpp);
// out of device memory is a LimitError naming --backend cpu.
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/generate/unstructured/subdivide.hpp"
#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::cuda {

// generate::contour(tets, options) on the GPU (options.backend is not read).
SurfaceMesh contour_tets(const UnstructuredGrid& tets, const generate::ContourOptions& options,
                         generate::ContourStats* stats = nullptr);

// generate::subdivide on the GPU (KeyReduce only).
SurfaceMesh subdivide(const SurfaceMesh& mesh, const generate::SubdivideOptions& options);
UnstructuredGrid subdivide(const UnstructuredGrid& tets, const generate::SubdivideOptions& options);

// generate::tetrahedralize5(grid) and tetrahedralize24(grid) on the GPU.
UnstructuredGrid tetrahedralize5(const ImageGrid& grid);
UnstructuredGrid tetrahedralize24(const ImageGrid& grid);

}  // namespace keymesh::cuda
