// VTK's SMP thread count for the vtkFlyingEdges3D peer (flying_edges_peer.cpp),
// in a file of its own: VTK 9.1's vtkSMPTools.h does not compile as C++20
// (a constructor declared with template arguments), so CMake builds this one
// file as C++17.
#include <vtkSMPTools.h>

namespace keymesh::bench {

void set_vtk_smp_threads(int threads) { vtkSMPTools::Initialize(threads); }

}  // namespace keymesh::bench
