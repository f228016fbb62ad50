"""Mesh/Grid <-> VTK and meshio: VTK's own filters accept what to_vtk gives,
round trips keep every array equal, and the arrays said to be shared are."""
import numpy as np
import pytest

import keymesh

vtk_np = pytest.importorskip("vtkmodules.util.numpy_support")


@pytest.fixture(scope="module")
def surface():
    i, j, k = np.indices((24, 27, 22), dtype=np.float32)
    f = np.cos(i * 0.31) + np.cos(j * 0.27) + np.cos(k * 0.35)   # a periodic "plumber's nightmare"
    return keymesh.contour(f, 0.37, normals="average", curvature=True)


@pytest.fixture(scope="module")
def tets():
    v = np.random.default_rng(9).random((6, 5, 7)).astype(np.float32)
    return keymesh.tetrahedralize(v, 5, spacing=(1.0, 0.5, 2.0))


def test_to_vtk_passes_vtk_filters_unchanged(surface):
    from vtkmodules.vtkFiltersCore import vtkCleanPolyData, vtkFeatureEdges

    poly = surface.to_vtk()
    assert poly.GetNumberOfPoints() == surface.n_points and poly.GetNumberOfCells() == surface.n_cells
    clean = vtkCleanPolyData()
    clean.SetInputData(poly)
    clean.PointMergingOn()
    clean.SetTolerance(0.0)
    clean.Update()
    out = clean.GetOutput()
    assert out.GetNumberOfPoints() == surface.n_points   # no duplicate or unused point
    assert out.GetNumberOfCells() == surface.n_cells     # no degenerate cell
    edges = vtkFeatureEdges()
    edges.SetInputData(poly)
    edges.BoundaryEdgesOn()
    edges.NonManifoldEdgesOn()
    edges.FeatureEdgesOff()
    edges.ManifoldEdgesOff()
    edges.Update()
    # the surface meets the box's faces (boundary edges there) and nowhere else
    lines = edges.GetOutput()
    pts = vtk_np.vtk_to_numpy(lines.GetPoints().GetData()) if lines.GetNumberOfPoints() else np.zeros((0, 3))
    hi = np.array([23, 26, 21], np.float32)
    on_box = np.any(np.isclose(pts, 0) | np.isclose(pts, hi), axis=1)
    assert np.all(on_box)
    assert keymesh.check(surface)["boundary_edges"] == lines.GetNumberOfCells()
    assert keymesh.check(surface)["nonmanifold_edges"] == 0


def test_vtk_round_trip_is_equal_and_shares_memory(surface):
    poly = surface.to_vtk()
    vtk_points = vtk_np.vtk_to_numpy(poly.GetPoints().GetData())
    assert np.shares_memory(vtk_points, surface.points)          # no copy of the points
    conn = vtk_np.vtk_to_numpy(poly.GetPolys().GetConnectivityArray())
    assert np.shares_memory(conn, surface.cells)                 # nor of the ids
    back = keymesh.from_vtk(poly)
    assert isinstance(back, keymesh.Mesh)
    assert np.array_equal(back.points, surface.points)
    assert np.array_equal(np.asarray(back.cells, np.int64), np.asarray(surface.cells, np.int64))
    assert set(back.point_data) == set(surface.point_data)
    for name, values in surface.point_data.items():
        assert np.array_equal(back.point_data[name], values)
        assert np.shares_memory(back.point_data[name], values)
    assert poly.GetPointData().GetNormals() is not None


def test_meshio_round_trip(surface, tmp_path):
    m = surface.to_meshio()
    assert np.shares_memory(m.points, surface.points)
    back = keymesh.from_meshio(m)
    assert np.array_equal(back.points, surface.points) and np.array_equal(back.cells, surface.cells)
    # through meshio's own writer and keymesh's reader
    import meshio

    meshio.write(tmp_path / "s.vtu", m)
    again = keymesh.from_meshio(meshio.read(tmp_path / "s.vtu"))
    assert np.array_equal(again.points, surface.points)
    assert np.array_equal(np.asarray(again.cells, np.int64), np.asarray(surface.cells, np.int64))
    for name, values in surface.point_data.items():
        assert np.array_equal(again.point_data[name], values)


def test_grid_to_vtk_volume_and_round_trip(tets):
    from vtkmodules.vtkFiltersVerdict import vtkCellSizeFilter

    ug = tets.to_vtk()
    assert ug.GetNumberOfCells() == tets.n_cells
    sizes = vtkCellSizeFilter()
    sizes.SetInputData(ug)
    sizes.ComputeSumOn()
    sizes.Update()
    vol = vtk_np.vtk_to_numpy(sizes.GetOutput().GetCellData().GetArray("Volume"))
    assert np.all(vol > 0) and np.isclose(vol.sum(), 5 * 4 * 6 * 1.0 * 0.5 * 2.0, rtol=1e-5)
    assert np.shares_memory(vtk_np.vtk_to_numpy(ug.GetPoints().GetData()), tets.points)
    back = keymesh.from_vtk(ug)
    assert isinstance(back, keymesh.Grid) and back.cell_type == 10
    assert np.array_equal(back.points, tets.points)
    assert np.array_equal(np.asarray(back.cells, np.int64), np.asarray(tets.cells, np.int64))
    assert np.array_equal(back.point_data["scalars"], tets.point_data["scalars"])


def test_grid_meshio_round_trip_and_files(tets, tmp_path):
    import meshio

    m = tets.to_meshio()
    assert m.cells[0].type == "tetra"
    meshio.write(tmp_path / "t.vtu", m)
    read_back = keymesh.read(tmp_path / "t.vtu")      # keymesh's reader on meshio's file
    assert isinstance(read_back, keymesh.Grid)
    assert np.array_equal(read_back.points, tets.points)
    assert np.array_equal(np.asarray(read_back.cells, np.int64), np.asarray(tets.cells, np.int64))
    keymesh.write(tets, tmp_path / "k.vtu")           # and meshio's reader on keymesh's file
    theirs = meshio.read(tmp_path / "k.vtu")
    back = keymesh.from_meshio(theirs)
    assert isinstance(back, keymesh.Grid)
    assert np.array_equal(np.asarray(back.cells, np.int64), np.asarray(tets.cells, np.int64))
    assert np.array_equal(back.point_data["scalars"], tets.point_data["scalars"])  # (n, 1) read as (n,)


def test_from_vtk_refuses_other_types():
    from vtkmodules.vtkCommonDataModel import vtkRectilinearGrid

    with pytest.raises(TypeError, match="vtkRectilinearGrid"):
        keymesh.from_vtk(vtkRectilinearGrid())


def test_volume_to_vtk_image_data():
    """VTK's own flying edges on Volume.to_vtk() finds keymesh's point count
    (one point per crossed edge) at the same positions; from_vtk gives the
    samples, spacing and origin back."""
    from vtkmodules.vtkFiltersCore import vtkFlyingEdges3D

    rng = np.random.default_rng(4)
    array = rng.standard_normal((17, 13, 11)).astype(np.float32)
    vol = keymesh.Volume(array, (0.5, 1.5, 2.0), (1.0, -2.0, 3.0))
    image = vol.to_vtk()
    assert np.shares_memory(vtk_np.vtk_to_numpy(image.GetPointData().GetScalars()), vol.array)
    fe = vtkFlyingEdges3D()
    fe.SetInputData(image)
    fe.SetValue(0, 0.1)
    fe.Update()
    theirs = vtk_np.vtk_to_numpy(fe.GetOutput().GetPoints().GetData())
    ours = keymesh.contour(vol, 0.1).points
    assert len(theirs) == len(ours)
    from conftest import match_points
    match_points(theirs, ours, tol=1e-4)
    back = keymesh.from_vtk(image)
    assert isinstance(back, keymesh.Volume)
    assert np.array_equal(back.array, array) and back.spacing == (0.5, 1.5, 2.0) and back.origin == (1.0, -2.0, 3.0)


def test_shared_arrays_outlive_their_first_owner():
    """The VTK object keeps the numpy memory it views alive after the Mesh
    or Grid is gone, and the views from_vtk returns keep VTK's arrays alive
    after the VTK object is gone (no dangling memory either way)."""
    import gc

    from vtkmodules.vtkFiltersCore import vtkCleanPolyData

    i, j, k = np.indices((20, 21, 22), dtype=np.float32)
    mesh = keymesh.contour(np.sqrt((i - 9.7) ** 2 + (j - 10.2) ** 2 + (k - 11.1) ** 2), 6.5)
    points, cells = mesh.points.copy(), np.asarray(mesh.cells, np.int64).copy()
    poly = mesh.to_vtk()
    del mesh
    gc.collect()
    junk = [np.full(len(points) * 3, 7.0, np.float32) for _ in range(20)]  # reuse freed memory, if any
    clean = vtkCleanPolyData()
    clean.SetInputData(poly)
    clean.Update()
    out = clean.GetOutput()   # VTK reads the shared memory (it renumbers points by first use)
    assert out.GetNumberOfPoints() == len(points) and out.GetNumberOfCells() == len(cells)
    assert np.array_equal(np.unique(vtk_np.vtk_to_numpy(out.GetPoints().GetData()), axis=0),
                          np.unique(points, axis=0))
    assert np.array_equal(vtk_np.vtk_to_numpy(poly.GetPoints().GetData()), points)
    assert np.array_equal(vtk_np.vtk_to_numpy(poly.GetPolys().GetConnectivityArray()), cells.reshape(-1))
    back = keymesh.from_vtk(poly)
    del poly, clean, out
    gc.collect()
    junk += [np.full(len(points) * 3, 7.0, np.float32) for _ in range(20)]
    assert np.array_equal(back.points, points) and np.array_equal(np.asarray(back.cells, np.int64), cells)
    assert keymesh.check(back)["closed_manifold"]
