"""keymesh.contour against vtkFlyingEdges3D (python3-vtk9), and the
vtkPolyData conversions."""
import numpy as np
import pytest

import keymesh
from conftest import match_points, noise_field, smooth_random_field, sphere_field

vtk = pytest.importorskip("vtkmodules.vtkFiltersCore")
from vtkmodules.util import numpy_support as ns  # noqa: E402
from vtkmodules.vtkCommonDataModel import vtkImageData  # noqa: E402


def flying_edges(field, iso):
    img = vtkImageData()
    img.SetDimensions(*field.shape)  # axis 0 = x: VTK's x-fastest order is Fortran order
    img.GetPointData().SetScalars(ns.numpy_to_vtk(np.ravel(field, order="F"), deep=True))
    fe = vtk.vtkFlyingEdges3D()
    fe.SetInputData(img)
    fe.SetValue(0, iso)
    fe.ComputeNormalsOff()
    fe.Update()
    return fe.GetOutput()


@pytest.mark.parametrize("make,iso", [(sphere_field, 12.37), (smooth_random_field, 0.0123), (noise_field, 0.0123)])
def test_same_counts_and_points_as_flying_edges(make, iso):
    field = make().astype(np.float32)
    mesh = keymesh.contour(field, iso)
    out = flying_edges(field, iso)
    assert mesh.n_points == out.GetNumberOfPoints() and mesh.n_cells == out.GetNumberOfCells()
    match_points(ns.vtk_to_numpy(out.GetPoints().GetData()), mesh.points)


def test_vtk_round_trip():
    mesh = keymesh.contour(sphere_field(), 12.37)
    poly = mesh.to_vtk()
    assert poly.GetNumberOfPoints() == mesh.n_points and poly.GetNumberOfPolys() == mesh.n_cells
    assert poly.GetPointData().GetNormals() is not None
    back = keymesh.Mesh.from_vtk(poly)
    assert np.array_equal(back.points, mesh.points) and np.array_equal(back.cells, mesh.cells)
    assert np.array_equal(back.point_data["scalars"], mesh.point_data["scalars"])
    # A VTK filter's output comes back too.
    fe = keymesh.from_vtk(flying_edges(sphere_field().astype(np.float32), 12.37))
    assert keymesh.check(fe)["closed_manifold"]
