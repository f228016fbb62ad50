#pragma once
// Marching cubes on the backend the options name: CPU threads
// (generate::contour) or an NVIDIA GPU (cuda::contour, byte-identical output).
//
// Why a layer of its own: generate's entry points run on the CPU, and the
// CUDA backend instantiates generate's device path (contour_device.hpp) on
// the GPU (cuda sits above generate), so the choice between them is made
// above both. The CLI calls this; the
// generators and the distributed and streamed contours call generate directly
// (they refuse --backend cuda by name).
#include "keymesh/generate/contour/contour.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::backend {

// options.backend == Backend::Cpu: generate::contour(grid, options, stats).
// Backend::Cuda: the same input checks as generate::contour (same
// InputError), then cuda::contour; a slab (options.total_planes) is refused
// by name, as is a build or a machine without a usable GPU.
// point_keys (the CPU only): generate::contour's, every point's edge key
// (history_key with options.history); the GPU refuses options.history.
SurfaceMesh contour(const ImageGrid& grid, const generate::ContourOptions& options,
                    generate::ContourStats* stats = nullptr, std::vector<std::uint64_t>* point_keys = nullptr);

// Marching tetrahedra on the backend the options name: generate::contour(tets)
// or, for Backend::Cuda, its input checks (the CPU's InputError), then what
// the GPU lacks refused by name (VERTEX-WELD, coarsening, history, point
// keys), then cuda::contour_tets.
SurfaceMesh contour(const UnstructuredGrid& tets, const generate::ContourOptions& options,
                    generate::ContourStats* stats = nullptr, std::vector<std::uint64_t>* point_keys = nullptr);

}  // namespace keymesh::backend
