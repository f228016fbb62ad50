#pragma once
// The voxel contour's device plans, one chosen by name (DevicePlan):
//  - Structured: count -> scan -> write, no soup, no sort
//                (contour_device_structured.hpp; the default, as on the CPU);
//  - Sort:       the soup of edge keys grouped by a radix sort, the paper's
//                GPU baseline (contour_device.hpp);
//  - VertexWeld: the soup of positions welded by coordinates, the paper's
//                Table 2 baseline (contour_device_vertex_weld.hpp).
// Each gives contour()'s bytes for the same weld (device_plan_for maps
// ContourOptions::weld to its plan): the two KEY-REDUCE plans the same mesh,
// VERTEX-WELD contour(..., VertexWeld)'s.
#include <limits>
#include <type_traits>
#include <utility>

#include "keymesh/generate/contour/contour_device.hpp"
#include "keymesh/generate/contour/contour_device_structured.hpp"
#include "keymesh/generate/contour/contour_device_vertex_weld.hpp"

namespace keymesh::generate {

enum class DevicePlan { Structured, Sort, VertexWeld };

// The plan that gives contour()'s mesh for `weld`: KeyReduce -> Structured,
// KeyReduceSort -> Sort, VertexWeld -> VertexWeld.
DevicePlan device_plan_for(ContourWeld weld);

// The options no device plan has (InputError naming them): history, output
// arrays, slabs and ghost planes. (Coarsening is contour_coarsened_on's,
// generate/coarsen/coarsen_device.hpp; the plans' entries refuse it.)
void check_device_plan_options(const ContourOptions& options);

// contour() through `plan` on the CPU device (what ctest compares with contour()).
SurfaceMesh contour_plan_on_cpu_device(const ImageGrid& grid, const ContourOptions& options, DevicePlan plan,
                                       ContourStats* stats = nullptr, DeviceKeys keys = DeviceKeys::Narrowest);

namespace device_contour {

// The arrays of `plan` (stats reset first) after contour()'s input checks
// and the plans' refusals; samples host memory, or the device's when
// `resident`. Keys: the soup plans' width (the structured plan has none).
template <class D>
ContourArrays<D> plan_arrays(const D& d, const ImageGrid& grid, bool resident, const ContourOptions& options,
                             ContourStats& st, DevicePlan plan, DeviceKeys keys) {
  check_contour_input(grid, options);
  check_device_plan_options(options);
  refuse_device_coarsen(options, "contour_plan_on");
  if (plan == DevicePlan::Sort) {
    ContourOptions sort = options;
    sort.weld = ContourWeld::KeyReduceSort;
    return checked_contour_arrays(d, grid, resident, sort, st, keys);
  }
  st = ContourStats{};
  const std::uint64_t key_range = 3ull * static_cast<std::uint64_t>(grid.num_points()) * options.isovalues.size();
  const bool narrow = keys == DeviceKeys::Narrowest && key_range <= std::numeric_limits<std::uint32_t>::max();
  return visit_scalars(grid, [&](const auto* samples) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(samples)>>;
    auto mark = d.begin_stage(&st.generate);
    const Input<D, T> in = prepare_input(d, grid, samples, resident, options);
    d.end_stage(mark);
    if (plan == DevicePlan::Structured) return device_structured::contour_arrays(d, in, options, st);
    if (narrow) return device_vertex_weld::contour_arrays<D, std::uint32_t, T>(d, in, options, st);
    return device_vertex_weld::contour_arrays<D, std::uint64_t, T>(d, in, options, st);
  });
}

}  // namespace device_contour

// `plan` on device `d`, the mesh brought to the host.
template <class D>
SurfaceMesh contour_plan_on(const D& d, const ImageGrid& grid, const ContourOptions& options, DevicePlan plan,
                            ContourStats* stats = nullptr, DeviceKeys keys = DeviceKeys::Narrowest) {
  ContourStats local;
  ContourStats& st = stats ? *stats : local;
  auto arrays = device_contour::plan_arrays(d, grid, false, options, st, plan, keys);
  return device_contour::to_host_mesh(d, std::move(arrays), grid.name, options, st);
}

// `plan` on samples already in the device's memory (contour_arrays_on's
// view: nothing uploaded), the mesh left there as device arrays.
template <class D>
device_contour::ContourArrays<D> contour_plan_arrays_on(const D& d, const ImageGrid& grid, const void* samples,
                                                        const ContourOptions& options, DevicePlan plan,
                                                        ContourStats* stats = nullptr,
                                                        DeviceKeys keys = DeviceKeys::Narrowest) {
  ContourStats local;
  return device_contour::plan_arrays(d, device_contour::samples_view(grid, samples), true, options,
                                     stats ? *stats : local, plan, keys);
}

}  // namespace keymesh::generate
