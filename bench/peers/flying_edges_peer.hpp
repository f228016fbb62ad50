#pragma once
// vtkFlyingEdges3D, the peer issue 17 measures the contour against, run on a
// keymesh ImageGrid's own samples (no copy) in the process that runs keymesh:
// contour_bench --peer fe3d. Built only where VTK's C++ package is installed
// (libvtk9-dev, one of `make bench`'s packages); contour_bench refuses the
// option by name otherwise.
#include <memory>
#include <vector>

#include "keymesh/mesh/image_grid.hpp"

namespace keymesh::bench {

class FlyingEdgesPeer {
 public:
  // Wraps the grid's samples (which must outlive the peer) and sets VTK's
  // SMP threads to `threads` (its TBB backend; 0 leaves VTK's default).
  FlyingEdgesPeer(const ImageGrid& grid, int threads);
  ~FlyingEdgesPeer();

  struct Run {
    double seconds = 0;  // a fresh filter's set-up and Update()
    long long points = 0, cells = 0;
  };
  // Contours at every isovalue in one filter, computing what contour_bench's
  // keymesh call does: positions and triangles, normals and gradients off,
  // the scalar only when `scalars`. The previous run's output is dropped
  // first, outside the timed part (as keymesh's mesh is).
  Run run(const std::vector<double>& isos, bool scalars);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keymesh::bench
