"""Cell fields (cell_data) through every path (issue 33, item 5): a label
surface's boundary_labels and label survive write/read (.vtp, .ply),
to/from meshio and VTK, and subdivide and coarsen carry them (each child
cell its parent's values; each kept triangle its own)."""

import numpy as np
import pytest

import keymesh

from conftest import smooth_random_field


@pytest.fixture(scope="module")
def labels():
    f = smooth_random_field((14, 13, 12), seed=3)
    vol = np.digitize(f, np.quantile(f, [0.4, 0.6, 0.8])).astype(np.uint8)
    mesh = keymesh.contour_labels(vol, method="discrete_marching_cubes")
    assert set(mesh.cell_data) == {"boundary_labels", "label"} and mesh.n_cells > 100
    assert len(np.unique(mesh.cell_data["boundary_labels"], axis=0)) > 2  # rows that can be told apart
    return mesh


def polygons():
    """A triangle, a quad and a triangle, with a cell field per cell."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], np.float32)
    cells = np.array([0, 1, 2, 1, 4, 5, 2, 2, 5, 3])
    offsets = np.array([0, 3, 7, 10])
    return keymesh.Mesh(pts, cells, offsets=offsets,
                        cell_data={"id": np.array([10.0, 20.0, 30.0], np.float32),
                                   "pair": np.array([[1, 2], [3, 4], [5, 6]], np.float32)})


def cells_with_data(mesh, name):
    """{polygon as a tuple of point ids: its row of cell_data[name]}."""
    data = np.asarray(mesh.cell_data[name])
    return {tuple(int(i) for i in c): tuple(np.atleast_1d(data[n]).tolist()) for n, c in enumerate(mesh.polygons())}


def assert_same_cell_data(a, b):
    assert set(a.cell_data) == set(b.cell_data), (set(a.cell_data), set(b.cell_data))
    for name, values in a.cell_data.items():
        got = np.asarray(b.cell_data[name])
        assert got.shape == np.shape(values) and np.array_equal(got, values), name


@pytest.mark.parametrize("ext", ["vtp", "ply"])
def test_write_and_read_keep_cell_data(labels, tmp_path, ext):
    path = str(tmp_path / f"l.{ext}")
    keymesh.write(labels, path)
    back = keymesh.read(path)
    assert np.array_equal(back.cells, labels.cells)
    assert_same_cell_data(labels, back)


@pytest.mark.parametrize("ext", ["vtp", "ply"])
def test_polygon_cell_data_through_files(tmp_path, ext):
    mesh = polygons()
    path = str(tmp_path / f"p.{ext}")
    keymesh.write(mesh, path)
    back = keymesh.read(path)
    assert np.array_equal(back.offsets, mesh.offsets)
    assert_same_cell_data(mesh, back)


def test_meshio_round_trip_keeps_cell_data(labels):
    pytest.importorskip("meshio")
    m = labels.to_meshio()
    assert set(m.cell_data) == {"boundary_labels", "label"}
    assert np.array_equal(m.cell_data["boundary_labels"][0], labels.cell_data["boundary_labels"])
    assert_same_cell_data(labels, keymesh.from_meshio(m))
    assert_same_cell_data(labels, keymesh.Mesh.from_meshio(m))


def test_meshio_regrouped_polygons_keep_their_cell_data():
    pytest.importorskip("meshio")
    mesh = polygons()
    m = mesh.to_meshio()
    assert [b.type for b in m.cells] == ["triangle", "quad"]  # regrouped by size
    back = keymesh.from_meshio(m)
    for name in ("id", "pair"):
        assert cells_with_data(back, name) == cells_with_data(mesh, name)


def test_vtk_round_trip_keeps_cell_data(labels):
    pytest.importorskip("vtkmodules.util.numpy_support")
    poly = labels.to_vtk()
    assert poly.GetCellData().GetArray("boundary_labels").GetNumberOfComponents() == 2
    assert_same_cell_data(labels, keymesh.from_vtk(poly))
    assert_same_cell_data(polygons(), keymesh.from_vtk(polygons().to_vtk()))


def test_subdivide_gives_children_their_parents_values(labels):
    fine = keymesh.subdivide(labels, 2)
    assert fine.n_cells == 16 * labels.n_cells
    for name, values in labels.cell_data.items():
        assert np.array_equal(fine.cell_data[name], np.repeat(values, 16, axis=0)), name


def test_coarsen_keeps_each_kept_triangles_values(labels):
    ids = np.arange(labels.n_cells, dtype=np.float32)
    mesh = keymesh.Mesh(labels.points, labels.cells, cell_data=dict(labels.cell_data, id=ids))
    coarse = keymesh.coarsen(mesh, spacing=(2.0, 2.0, 2.0))
    assert 0 < coarse.n_cells < mesh.n_cells
    kept = coarse.cell_data["id"].astype(np.int64)
    assert np.array_equal(kept, ids[kept]) and (np.diff(kept) > 0).all()  # a subsequence, in order
    for name, values in labels.cell_data.items():
        assert np.array_equal(coarse.cell_data[name], np.asarray(values)[kept]), name
    # Each kept triangle is where its input triangle was, up to the lattice's merging.
    centre_in = labels.points[labels.cells[kept].astype(np.int64)].mean(axis=1)
    centre_out = coarse.points[coarse.cells.astype(np.int64)].mean(axis=1)
    assert np.abs(centre_out - centre_in).max() < 2.0


def test_wrong_cell_data_rows_refused(tmp_path):
    mesh = polygons()
    mesh.cell_data["id"] = np.zeros(4, np.float32)
    with pytest.raises(ValueError, match="cell_data"):
        keymesh.write(mesh, str(tmp_path / "bad.vtp"))

