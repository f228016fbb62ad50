"""keymesh.contour_labels (issue 18) from Python: the same mesh as the
command (written .vtp read back by VTK), the axis convention, per-label
topology against skimage.measure.euler_number, and refusals."""
import os
import subprocess
import sys
import tempfile

import numpy as np
import pytest

import keymesh

from conftest import smooth_random_field

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import junction_labels  # noqa: E402
from mesh_checks import assert_closed_manifold  # noqa: E402


def label_map(shape=(20, 17, 15), seed=5):
    """Three labels and background from a smooth random field's bands."""
    f = smooth_random_field(shape, seed=seed)
    return np.digitize(f, np.quantile(f, [0.4, 0.6, 0.8])).astype(np.uint8)


def test_matches_command_and_axis_convention():
    vol = label_map()
    mesh = keymesh.contour_labels(vol, spacing=(1.0, 2.0, 0.5), smoothing=False)
    assert mesh.cell_data["boundary_labels"].shape == (mesh.n_cells, 2)
    bl = mesh.cell_data["boundary_labels"]
    assert (bl[:, 0] < bl[:, 1]).all()
    # One point per cell of the padded grid whose corners hold two labels or more.
    p = np.pad(vol, 1)
    c = np.stack([p[i:p.shape[0] - 1 + i, j:p.shape[1] - 1 + j, k:p.shape[2] - 1 + k]
                  for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    assert mesh.n_points == int((c != c[0]).any(axis=0).sum())
    # Axis 0 is x: cell centres at (i - 0.5) * spacing.
    assert np.isclose(mesh.points[:, 0].min(), -0.5) and np.isclose(mesh.points[:, 1].max(), (vol.shape[1] - 0.5) * 2)
    # C and Fortran order give the same mesh.
    other = keymesh.contour_labels(np.asfortranarray(vol), spacing=(1.0, 2.0, 0.5), smoothing=False)
    assert (other.cells == mesh.cells).all() and (other.points == mesh.points).all()
    # The command on the same volume written as .vti gives the same points and faces.
    poly, ns = _command_mesh(vol, "--smooth", "0")
    assert poly.GetNumberOfPoints() == mesh.n_points and poly.GetNumberOfPolys() == mesh.n_cells
    theirs = ns.vtk_to_numpy(poly.GetCellData().GetArray("boundary_labels"))
    assert (theirs == bl).all()


def _command_mesh(vol, *args):
    """`keymesh labels` on vol (written as .vti) with args: (vtkPolyData, numpy_support)."""
    vtk = pytest.importorskip("vtk")
    from vtk.util import numpy_support as ns
    binary = os.environ.get("KEYMESH", os.path.join(os.path.dirname(keymesh.__file__), "..", "..", "keymesh"))
    if not os.path.exists(binary):
        pytest.skip("keymesh command not found")
    with tempfile.TemporaryDirectory() as d:
        vol_path, out = os.path.join(d, "v.vti"), os.path.join(d, "v.vtp")
        _vti(vol, vol_path)
        subprocess.run([binary, "labels", vol_path, "-o", out, *args, "-q"], check=True)
        r = vtk.vtkXMLPolyDataReader()
        r.SetFileName(out)
        r.Update()
        poly = vtk.vtkPolyData()
        poly.DeepCopy(r.GetOutput())
        return poly, ns


def _vti(vol, path):
    """vol (axis 0 = x) as an ascii .vti with spacing (1, 2, 0.5), by hand."""
    nx, ny, nz = vol.shape
    data = " ".join(str(int(v)) for v in vol.reshape(-1, order="F"))
    with open(path, "w") as f:
        f.write(f'<?xml version="1.0"?>\n<VTKFile type="ImageData" version="0.1" byte_order="LittleEndian">\n'
                f'<ImageData WholeExtent="0 {nx - 1} 0 {ny - 1} 0 {nz - 1}" Origin="0 0 0" Spacing="1 2 0.5">\n'
                f'<Piece Extent="0 {nx - 1} 0 {ny - 1} 0 {nz - 1}"><PointData Scalars="labels">\n'
                f'<DataArray type="UInt8" Name="labels" format="ascii">{data}</DataArray>\n'
                f'</PointData><CellData/></Piece></ImageData></VTKFile>\n')


@pytest.mark.parametrize("method", ["surface_nets", "discrete_marching_cubes"])
def test_per_label_euler(method):
    skimage_measure = pytest.importorskip("skimage.measure")
    vol = label_map(seed=9)
    mesh = keymesh.contour_labels(vol, method=method, per_label=True, smoothing=False)
    labels = mesh.cell_data["label"]
    for lab in (1, 2, 3):
        t = mesh.cells[labels == lab].astype(np.int64)
        edges = np.unique(np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1), axis=0)
        chi = len(np.unique(t)) - len(edges) + len(t)
        region = np.pad(vol == lab, 1)
        expected = 2 * (skimage_measure.euler_number(region, connectivity=1) + filled_rings(region))
        # Every directed edge once, with its reverse: closed and oriented.
        directed = {tuple(e) for e in np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])}
        assert len(directed) == 3 * len(t) and all((b, a) in directed for a, b in directed), (method, lab)
        assert chi == expected, (method, lab, chi, expected)


def filled_rings(region):
    """Cubes (2x2x2 blocks) whose only outside corners are the two ends of
    a body diagonal: the marching cubes table (VTK's too) joins the six
    inside corners around it, a ring 6-connectivity leaves open, adding 1 to
    the Euler number each (labels.hpp)."""
    c = np.stack([region[i:region.shape[0] - 1 + i, j:region.shape[1] - 1 + j, k:region.shape[2] - 1 + k]
                  for k in (0, 1) for j in (0, 1) for i in (0, 1)])
    out = ~c
    return int(sum(((out.sum(0) == 2) & out[a] & out[7 - a]).sum() for a in range(4)))


def test_threads_and_smoothing():
    vol = label_map()
    a = keymesh.contour_labels(vol, threads=1)
    b = keymesh.contour_labels(vol, threads=2)
    assert (a.points == b.points).all() and (a.cells == b.cells).all()
    raw = keymesh.contour_labels(vol, smoothing=False)
    assert (np.abs(a.points - raw.points) <= 0.5 + 1e-6).all() and np.abs(a.points - raw.points).max() > 0


def test_guard_shortened_reported():
    """last_labels_info["guard_shortened"]: the smoothing moves the fold
    guard shortened or refused; > 0 where labels meet all over, the same at
    1 and 2 threads, 0 unsmoothed."""
    from keymesh._labels import last_labels_info
    vol = junction_labels((20, 18, 16), 12, 2)
    keymesh.contour_labels(vol, threads=1)
    smoothed = last_labels_info["guard_shortened"]
    assert smoothed > 0
    keymesh.contour_labels(vol, threads=2)
    assert last_labels_info["guard_shortened"] == smoothed
    keymesh.contour_labels(vol, smoothing=False)
    assert last_labels_info["guard_shortened"] == 0


def test_refused():
    with pytest.raises(keymesh.Error, match="float32"):
        keymesh.contour_labels(np.zeros((4, 4, 4), np.float32))
    with pytest.raises(keymesh.Error, match="no voxel of label 7"):
        keymesh.contour_labels(label_map(), labels=[7])
    with pytest.raises(ValueError, match="method"):
        keymesh.contour_labels(label_map(), method="marching")


@pytest.mark.parametrize("seed", range(12))
def test_white_noise_per_label_closed_manifolds(seed):
    """Every ambiguous configuration occurs: each label's surface (both methods)
    is closed and oriented, every vertex's triangles one fan, Euler as stated."""
    skimage_measure = pytest.importorskip("skimage.measure")
    rng = np.random.default_rng(seed)
    shape = (9, 8, 7) if seed % 2 else (10, 9, 8)
    vol = (rng.integers(0, 4, size=shape) if seed % 2
           else (rng.random(shape) < 0.5) * rng.integers(1, 3, size=shape)).astype(np.uint8)
    for method in ("surface_nets", "discrete_marching_cubes"):
        mesh = keymesh.contour_labels(vol, method=method, per_label=True, smoothing=False)
        for lab in (int(x) for x in np.unique(vol) if x):
            t = mesh.cells[mesh.cell_data["label"] == lab].astype(np.int64)
            assert_closed_manifold(t, f"{method} label {lab}")
            directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
            edges = np.unique(np.sort(directed, axis=1), axis=0)
            region = np.pad(vol == lab, 1)
            expected = 2 * (skimage_measure.euler_number(region, connectivity=1) + filled_rings(region))
            assert len(np.unique(t)) - len(edges) + len(t) == expected, (method, lab)


@pytest.mark.parametrize("method", ["surface_nets", "discrete_marching_cubes"])
def test_coarsen_matches_the_command(method):
    """coarsen=True is `keymesh labels --coarsen`: the same points and faces,
    fewer of them than without, every point used by a face."""
    vol = label_map(seed=9)
    fine = keymesh.contour_labels(vol, spacing=(1.0, 2.0, 0.5), method=method, smoothing_iterations=4)
    mesh = keymesh.contour_labels(vol, spacing=(1.0, 2.0, 0.5), method=method, smoothing_iterations=4, coarsen=True)
    assert 0 < mesh.n_cells < fine.n_cells and mesh.n_points < fine.n_points
    assert len(np.unique(mesh.cells)) == mesh.n_points
    cli_method = "surfacenets" if method == "surface_nets" else "discrete-mc"
    poly, ns = _command_mesh(vol, "--method", cli_method, "--smooth", "4", "--coarsen")
    theirs = ns.vtk_to_numpy(poly.GetPoints().GetData())
    assert theirs.shape == mesh.points.shape and np.array_equal(theirs, mesh.points)
    cells = ns.vtk_to_numpy(poly.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    assert np.array_equal(cells, mesh.cells)
