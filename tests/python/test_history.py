"""keymesh.contour(..., history=True): point_data["history_key"] (uint64) and
point_data["history_t"] (float32), as `keymesh contour --history` writes
them (docs/HISTORY.md)."""
import os
import shutil
import subprocess
import tempfile

import numpy as np
import pytest

import keymesh
from conftest import history_positions, smooth_random_field

SPACING = (0.5, 0.75, 1.25)
ORIGIN = (3.0, 1.5, 2.0)
ISOS = [-0.05, 0.0, 0.08]


def volume():
    v = smooth_random_field((19, 17, 15), seed=12).astype(np.float32)
    v[::4, ::3, ::5] = np.float32(0.0)  # samples on an isovalue: t = 0 or 1
    return v


def decode(key, shape):
    """isovalue index, lower grid point (i, j, k) and axis of each key (axis 0 of the array is x)."""
    nx, ny, nz = shape
    n = nx * ny * nz
    iso, edge = key // (3 * n), key % (3 * n)
    point, axis = edge // 3, edge % 3
    ijk = np.stack([point % nx, point // nx % ny, point // (nx * ny)], axis=1).astype(np.int64)
    return iso.astype(np.int64), ijk, axis.astype(np.int64)


def contour(v, **kw):
    return keymesh.contour(v, ISOS, spacing=SPACING, origin=ORIGIN, normals="none", history=True, **kw)


def by_key(m):
    order = np.argsort(m.point_data["history_key"])
    return (m.point_data["history_key"][order], m.point_data["history_t"][order], m.points[order])


def test_arrays_and_dtypes():
    m = contour(volume())
    key, t = m.point_data["history_key"], m.point_data["history_t"]
    assert key.dtype == np.uint64 and t.dtype == np.float32
    assert key.shape == t.shape == (len(m.points),)
    assert len(np.unique(key)) == len(key)
    assert t.min() >= 0 and t.max() <= 1


def test_positions_reproduced_exactly():
    v = volume()
    m = contour(v)
    _, ijk, axis = decode(m.point_data["history_key"], v.shape)
    assert np.array_equal(history_positions(ijk, axis, m.point_data["history_t"], ORIGIN, SPACING), m.points)


def test_every_memory_order_and_thread_count_gives_the_same_history():
    v = volume()
    ref = by_key(contour(v, threads=1))
    for other in (contour(v, threads=2), contour(np.asfortranarray(v)), contour(v[:, :, :].copy(order="C"))):
        got = by_key(other)
        for a, b in zip(ref, got):
            assert np.array_equal(a, b)
    vol = keymesh.Volume(np.asfortranarray(v), spacing=SPACING, origin=ORIGIN)
    got = by_key(keymesh.contour(vol, ISOS, normals="none", history=True))
    for a, b in zip(ref, got):
        assert np.array_equal(a, b)


def test_attribute_transfer():
    """A second field carried by history: exact for a linear field (linear
    along every edge), and the contoured field itself gives keymesh's own
    interpolated scalar back."""
    v = volume()
    m = contour(v)
    key, t = m.point_data["history_key"], m.point_data["history_t"].astype(np.float64)
    _, ijk, axis = decode(key, v.shape)
    far = ijk.copy()
    far[np.arange(len(far)), axis] += 1

    def carried(field):
        a0 = field[ijk[:, 0], ijk[:, 1], ijk[:, 2]]
        a1 = field[far[:, 0], far[:, 1], far[:, 2]]
        return a0 + t * (a1 - a0)

    i, j, k = np.indices(v.shape, dtype=np.float64)
    x, y, z = (np.array(ORIGIN)[:, None, None, None] +
               np.array(SPACING)[:, None, None, None] * np.stack([i, j, k]))
    linear = 0.7 * x - 1.3 * y + 0.4 * z + 2.0
    p = m.points.astype(np.float64)
    analytic = 0.7 * p[:, 0] - 1.3 * p[:, 1] + 0.4 * p[:, 2] + 2.0
    np.testing.assert_allclose(carried(linear), analytic, rtol=0, atol=1e-5)
    # The contoured field: keymesh's scalar (interpolated with the double t).
    scalars = m.point_data["scalars"].astype(np.float64)
    span = np.abs(v.max() - v.min())
    np.testing.assert_allclose(carried(v.astype(np.float64)), scalars, rtol=0, atol=span * 2.0 ** -20)


def test_coarsen_is_refused():
    with pytest.raises(ValueError, match="coarsen"):
        contour(volume(), coarsen=True)


def test_equals_the_command_line():
    exe = os.environ.get("KEYMESH")
    vtk = pytest.importorskip("vtk")
    from vtk.util import numpy_support as ns
    if not exe or not shutil.which(exe):
        pytest.skip("no keymesh binary (KEYMESH)")
    v = volume()
    with tempfile.TemporaryDirectory() as d:
        raw, out = os.path.join(d, "v.raw"), os.path.join(d, "v.vtp")
        np.asfortranarray(v).ravel(order="F").tofile(raw)  # x fastest
        args = [exe, "contour", raw, "--dims", *map(str, v.shape), "--type", "float32",
                "--spacing", *map(str, SPACING), "--origin", *map(str, ORIGIN), "--history", "-o", out, "-q",
                "--normals", "none"]
        for iso in ISOS:
            args += ["--iso", str(iso)]
        subprocess.run(args, check=True)
        reader = vtk.vtkXMLPolyDataReader()
        reader.SetFileName(out)
        reader.Update()
        poly = reader.GetOutput()
        key = ns.vtk_to_numpy(poly.GetPointData().GetArray("history_key")).astype(np.uint64)
        t = ns.vtk_to_numpy(poly.GetPointData().GetArray("history_t"))
        points = ns.vtk_to_numpy(poly.GetPoints().GetData())
    order = np.argsort(key)
    for a, b in zip(by_key(contour(v)), (key[order], t[order], points[order])):
        assert np.array_equal(a, b)


def test_write_keeps_history_key_uint64():
    vtk = pytest.importorskip("vtk")
    from vtk.util import numpy_support as ns
    m = contour(volume())
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "h.vtp")
        keymesh.write(m, out)
        reader = vtk.vtkXMLPolyDataReader()
        reader.SetFileName(out)
        reader.Update()
        pd = reader.GetOutput().GetPointData()
        key = ns.vtk_to_numpy(pd.GetArray("history_key"))
        assert key.dtype == np.uint64
        assert np.array_equal(key, m.point_data["history_key"])
        assert np.array_equal(ns.vtk_to_numpy(pd.GetArray("history_t")), m.point_data["history_t"])
        for ext in ("ply", "obj"):
            path = os.path.join(d, "h." + ext)
            with pytest.raises(ValueError, match="only .vtp"):
                keymesh.write(m, path)
            assert not os.path.exists(path)


def test_gpu_backend_refuses_history_by_name():
    # Refused before any device is considered: the same on a machine with or without a GPU.
    with pytest.raises(ValueError, match=r"per-point history \(--history\)"):
        contour(volume(), backend="cuda")
