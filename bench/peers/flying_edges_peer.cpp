#include "flying_edges_peer.hpp"

#include <vtkAOSDataArrayTemplate.h>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <chrono>
#include <cstdint>

namespace keymesh::bench {

// vtk_smp_threads.cpp: VTK 9.1's vtkSMPTools.h does not compile as C++20.
void set_vtk_smp_threads(int threads);

struct FlyingEdgesPeer::Impl {
  vtkSmartPointer<vtkImageData> image;
  vtkSmartPointer<vtkPolyData> last;  // the previous run's output, dropped before the next run
};

namespace {

// A VTK array over `samples` that never frees them (save = 1).
template <class T>
vtkSmartPointer<vtkDataArray> view(const T* samples, vtkIdType n) {
  auto array = vtkSmartPointer<vtkAOSDataArrayTemplate<T>>::New();
  array->SetArray(const_cast<T*>(samples), n, 1);
  array->SetName("v");
  return array;
}

}  // namespace

FlyingEdgesPeer::FlyingEdgesPeer(const ImageGrid& grid, int threads) : impl_(std::make_unique<Impl>()) {
  if (threads > 0) set_vtk_smp_threads(threads);
  impl_->image = vtkSmartPointer<vtkImageData>::New();
  impl_->image->SetDimensions(static_cast<int>(grid.dims[0]), static_cast<int>(grid.dims[1]),
                              static_cast<int>(grid.dims[2]));
  impl_->image->SetOrigin(grid.origin.data());
  impl_->image->SetSpacing(grid.spacing.data());
  const auto n = static_cast<vtkIdType>(grid.num_points());
  impl_->image->GetPointData()->SetScalars(
      visit_scalars(grid, [n](const auto* samples) { return view(samples, n); }));
}

FlyingEdgesPeer::~FlyingEdgesPeer() = default;

FlyingEdgesPeer::Run FlyingEdgesPeer::run(const std::vector<double>& isos, bool scalars) {
  impl_->last = nullptr;
  const auto t0 = std::chrono::steady_clock::now();
  auto filter = vtkSmartPointer<vtkFlyingEdges3D>::New();
  filter->SetInputData(impl_->image);
  for (std::size_t i = 0; i < isos.size(); ++i) filter->SetValue(static_cast<int>(i), isos[i]);
  filter->ComputeNormalsOff();
  filter->ComputeGradientsOff();
  filter->SetComputeScalars(scalars);
  filter->Update();
  Run r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  impl_->last = filter->GetOutput();
  r.points = impl_->last->GetNumberOfPoints();
  r.cells = impl_->last->GetNumberOfCells();
  return r;
}

}  // namespace keymesh::bench
