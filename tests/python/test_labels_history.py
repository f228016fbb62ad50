"""keymesh.contour_labels(..., history=True) and keymesh.dask.contour_labels:
point_data["history_key"] (uint64) and ["history_t"] (float32), as
`keymesh labels --history` writes them (docs/HISTORY.md). Keys decoded in
numpy, in the array padded with one sample of background all round
(array index (i, j, k) is padded point ravel((i+1, j+1, k+1), shape + 2, F))."""
import numpy as np
import pytest

import keymesh
from conftest import history_positions

SPACING = (0.5, 0.75, 1.25)
ORIGIN = (3.0, -1.5, 2.0)


def label_volume(shape=(9, 8, 11), seed=4):
    rng = np.random.default_rng(seed)
    v = np.zeros(shape, np.int16)
    v[1:6, 2:7, 2:8] = 5
    v[3:8, 1:6, 5:10] = 9
    noise = rng.random(shape) < 0.25
    v[noise] = rng.integers(0, 4, size=noise.sum())
    return v


def padded_ijk(p, shape):
    px, py, _ = np.add(shape, 2)
    return np.stack([p % px, p // px % py, p // (px * py)], axis=1)


def at(u):
    return (np.array(ORIGIN) + np.array(SPACING) * u).astype(np.float32)


def run(v, **kw):
    kw.setdefault("smoothing", False)
    return keymesh.contour_labels(v, spacing=SPACING, origin=ORIGIN, history=True, **kw)


def test_discrete_mc_points_from_key_and_t():
    v = label_volume()
    m = run(v, method="discrete_marching_cubes")
    key, t = m.point_data["history_key"], m.point_data["history_t"]
    assert key.dtype == np.uint64 and t.dtype == np.float32 and len(key) == len(m.points)
    assert np.all(t == np.float32(0.5))
    p, axis = (key // 3).astype(np.int64), (key % 3).astype(np.int64)
    ijk = padded_ijk(p, v.shape)
    padded = np.pad(v, 1)
    far = ijk.copy()
    far[np.arange(len(far)), axis] += 1
    assert np.all(padded[tuple(ijk.T)] != padded[tuple(far.T)]), "an edge between equal labels"
    assert np.array_equal(history_positions(ijk - 1, axis, t, ORIGIN, SPACING), m.points)
    assert len(np.unique(key)) == len(key)


def test_surface_nets_points_are_cell_centres():
    v = label_volume()
    m = run(v)
    key, t = m.point_data["history_key"], m.point_data["history_t"]
    assert np.all(key % 16 == 0) and np.all(t == np.float32(0.5))
    ijk = padded_ijk((key // 16).astype(np.int64), v.shape)
    assert np.array_equal(at(ijk - 1 + t[:, None].astype(np.float64)), m.points)
    # every cell named has more than one label at its 8 corners
    padded = np.pad(v, 1)
    corners = np.stack([padded[tuple((ijk + d).T)] for d in np.ndindex(2, 2, 2)])
    assert np.all(corners.min(axis=0) != corners.max(axis=0))


@pytest.mark.parametrize("method", ["surface_nets", "discrete_marching_cubes"])
def test_smoothing_and_memory_order_keep_the_keys(method):
    v = label_volume()
    plain = run(v, method=method, per_label=True)
    smooth = run(v, method=method, per_label=True, smoothing=True)
    c_order = run(np.ascontiguousarray(v), method=method, per_label=True, smoothing=True)
    f_order = run(np.asfortranarray(v), method=method, per_label=True, smoothing=True)
    for m in (smooth, c_order, f_order):
        assert np.array_equal(m.point_data["history_key"], plain.point_data["history_key"])
        assert np.array_equal(m.point_data["history_t"], plain.point_data["history_t"])
        assert np.array_equal(m.cells, plain.cells)
    assert np.array_equal(c_order.points, f_order.points)
    assert not np.array_equal(smooth.points, plain.points)


def test_without_history_no_arrays_and_coarsen_refused():
    v = label_volume()
    m = keymesh.contour_labels(v)
    assert "history_key" not in m.point_data and "history_t" not in m.point_data
    with pytest.raises(keymesh.Error, match="coarsen"):
        keymesh.contour_labels(v, history=True, coarsen=True)
    keymesh.contour_labels(v)  # the interpreter is alive


@pytest.mark.parametrize("per_label", [False, True])
def test_dask_equals_in_memory(per_label):
    da = pytest.importorskip("dask.array")
    v = label_volume()
    ref = run(v, per_label=per_label, smoothing=True)
    m = keymesh.dask.contour_labels(da.from_array(v, chunks=(9, 8, 4)), spacing=SPACING, origin=ORIGIN,
                                    per_label=per_label, history=True, scheduler="synchronous")
    assert np.array_equal(m.point_data["history_key"], ref.point_data["history_key"])
    assert np.array_equal(m.point_data["history_t"], ref.point_data["history_t"])
    assert np.array_equal(m.points, ref.points)
