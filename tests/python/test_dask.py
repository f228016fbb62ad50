"""keymesh.dask (issue 36): contours of chunked Dask arrays equal the
in-memory calls bit for bit, for any chunking, on the threaded scheduler and
on a dask.distributed cluster."""
import numpy as np
import pytest

import keymesh

da = pytest.importorskip("dask.array")
import keymesh.dask  # noqa: E402  (needs dask)

from conftest import noise_field, smooth_random_field, sphere_field  # noqa: E402


def assert_same(got, want):
    """The same mesh: points, cells, their order, every field, bit for bit."""
    assert got.points.dtype == want.points.dtype and got.cells.dtype == want.cells.dtype
    assert np.array_equal(got.points, want.points), (got.points.shape, want.points.shape)
    assert np.array_equal(got.cells, want.cells), (got.cells.shape, want.cells.shape)
    for mine, theirs in ((got.point_data, want.point_data), (got.cell_data, want.cell_data)):
        assert list(mine) == list(theirs)
        for name in theirs:
            assert mine[name].dtype == theirs[name].dtype, name
            assert np.array_equal(mine[name], theirs[name]), name


# Chunkings of a (23, 19, 21) volume: even, uneven, one- and two-sample chunks.
CHUNKINGS = [
    (8, 7, 6),
    ((5, 1, 10, 7), (19,), (2, 9, 10)),
    ((2, 21), (1, 18), (20, 1)),
    (23, 19, 21),
]


@pytest.mark.parametrize("chunks", CHUNKINGS)
@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.uint8, np.int16])
def test_contour_equals_in_memory(chunks, dtype):
    field = smooth_random_field((23, 19, 21), seed=11)
    if np.dtype(dtype).kind in "iu":
        field = (field - field.min()) / (field.max() - field.min()) * 200
        iso = [60.5, 101.0]
    else:
        iso = [0.0, 0.05]
    vol = field.astype(dtype)
    want = keymesh.contour(vol, iso, spacing=(0.7, 1.1, 1.3), origin=(-3.0, 2.5, 0.25))
    got = keymesh.dask.contour(da.from_array(vol, chunks=chunks), iso, spacing=(0.7, 1.1, 1.3),
                               origin=(-3.0, 2.5, 0.25))
    assert want.n_cells > 1000
    assert_same(got, want)


def test_tiny_chunks_every_axis():
    """Chunks of one sample along every axis: every voxel a task of its own."""
    vol = noise_field((7, 6, 5), seed=4)
    got = keymesh.dask.contour(da.from_array(vol, chunks=1), 0.1)
    assert_same(got, keymesh.contour(vol, 0.1))


@pytest.mark.parametrize("options", [
    dict(normals="gradient"),
    dict(normals="none", scalars=False),
    dict(normals="gradient", curvature=True),
    dict(coarsen=True),
    dict(coarsen=True, normals="none"),
    dict(weld="keyreduce-sort"),
])
def test_contour_options(options):
    vol = sphere_field((21, 18, 23), center=(10.3, 8.9, 11.6)) + 0.3 * noise_field((21, 18, 23), seed=2)
    iso = [4.5, 7.25]
    want = keymesh.contour(vol, iso, **options)
    got = keymesh.dask.contour(da.from_array(vol, chunks=((4, 1, 9, 7), 6, (2, 11, 10))), iso, **options)
    assert_same(got, want)


def test_memory_order():
    """order="C" equals the C-ordered array's contour, "F" the Fortran-ordered
    one's, whatever the chunks' own order."""
    vol = np.asfortranarray(noise_field((13, 11, 12), seed=8))
    arr = da.from_array(vol, chunks=(5, 4, 7))
    assert_same(keymesh.dask.contour(arr, 0.2), keymesh.contour(np.ascontiguousarray(vol), 0.2))
    assert_same(keymesh.dask.contour(arr, 0.2, order="F"), keymesh.contour(np.asfortranarray(vol), 0.2))
    c_arr = da.from_array(np.ascontiguousarray(vol), chunks=(6, 11, 5))
    assert_same(keymesh.dask.contour(c_arr, 0.2, order="F", normals="gradient"),
                keymesh.contour(np.asfortranarray(vol), 0.2, normals="gradient"))


def test_zarr_backed(tmp_path):
    zarr = pytest.importorskip("zarr")
    vol = smooth_random_field((22, 17, 19), seed=3).astype(np.float32)
    z = zarr.open(str(tmp_path / "v.zarr"), mode="w", shape=vol.shape, chunks=(9, 5, 8), dtype=vol.dtype)
    z[:] = vol
    arr = da.from_zarr(str(tmp_path / "v.zarr"))
    assert arr.chunks[1] == (5, 5, 5, 2)
    assert_same(keymesh.dask.contour(arr, [0.0, 0.03]), keymesh.contour(vol, [0.0, 0.03]))
    # A zarr.Array itself is wrapped with its own chunks.
    assert_same(keymesh.dask.contour(z, -0.02, coarsen=True), keymesh.contour(vol, -0.02, coarsen=True))


def test_distributed_local_cluster():
    distributed = pytest.importorskip("distributed")
    vol = sphere_field((19, 17, 16), center=(9.1, 8.2, 7.7))
    labels = np.digitize(smooth_random_field((14, 12, 13), seed=6), [-0.05, 0.05]).astype(np.uint8)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster):
        got = keymesh.dask.contour(da.from_array(vol, chunks=(5, 9, 6)), [3.5, 6.5])
        got_labels = keymesh.dask.contour_labels(da.from_array(labels, chunks=(7, 5, (4, 1, 8))))
    assert_same(got, keymesh.contour(vol, [3.5, 6.5]))
    assert_same(got_labels, keymesh.contour_labels(labels))


def test_distributed_worker_processes():
    """Workers in processes of their own: the tasks and their pieces are pickled."""
    distributed = pytest.importorskip("distributed")
    vol = sphere_field((16, 15, 14), center=(7.4, 7.1, 6.6)).astype(np.float32)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster):
        got = keymesh.dask.contour(da.from_array(vol, chunks=(6, 8, 5)), 4.5, coarsen=True)
    assert_same(got, keymesh.contour(vol, 4.5, coarsen=True))


def test_compute_false_gives_a_delayed():
    vol = sphere_field((12, 11, 10), center=(5.5, 5.2, 4.9))
    lazy = keymesh.dask.contour(da.from_array(vol, chunks=4), 3.0, compute=False)
    assert hasattr(lazy, "compute")
    assert_same(lazy.compute(scheduler="threads"), keymesh.contour(vol, 3.0))


def label_map(shape=(18, 15, 16), seed=5):
    """Three labels and background from a smooth random field's bands."""
    f = smooth_random_field(shape, seed=seed)
    return np.digitize(f, np.quantile(f, [0.4, 0.6, 0.8])).astype(np.uint8)


@pytest.mark.parametrize("chunks", [(6, 5, 4), ((18,), (15,), (1, 2, 12, 1)), (18, 15, 16)])
@pytest.mark.parametrize("options", [
    dict(),
    dict(smoothing=False),
    dict(method="discrete_marching_cubes"),
    dict(per_label=True),
    dict(coarsen=True),
    dict(method="discrete_marching_cubes", per_label=True, coarsen=True),
    dict(labels=[1, 3], background=2, spacing=(1.0, 2.0, 0.5), origin=(1.0, 0.0, -2.0)),
])
def test_contour_labels_equals_in_memory(chunks, options):
    vol = label_map()
    want = keymesh.contour_labels(vol, **options)
    got = keymesh.dask.contour_labels(da.from_array(vol, chunks=chunks), **options)
    assert isinstance(got, keymesh.LabelMesh)
    assert want.n_cells > 500
    assert_same(got, want)


def test_contour_labels_dtypes_and_order():
    vol = label_map(seed=9).astype(np.int16) - 1
    want = keymesh.contour_labels(vol, background=-1)
    arr = da.from_array(np.asfortranarray(vol), chunks=(7, 8, 3))
    assert_same(keymesh.dask.contour_labels(arr, background=-1), want)


def test_refused():
    vol = da.from_array(noise_field((6, 5, 4)), chunks=3)
    with pytest.raises(ValueError, match="vertexweld"):
        keymesh.dask.contour(vol, 0.0, weld="vertexweld")
    with pytest.raises(ValueError, match="finite"):
        keymesh.dask.contour(vol, float("nan"))
    with pytest.raises(ValueError, match="order"):
        keymesh.dask.contour(vol, 0.0, order="K")
    with pytest.raises(ValueError, match="3-D"):
        keymesh.dask.contour(da.zeros((4, 4), chunks=2), 0.0)
    with pytest.raises(keymesh.Error, match="need at least 2"):
        keymesh.dask.contour(da.zeros((4, 1, 4), chunks=2), 0.0)
    with pytest.raises(TypeError, match="complex128"):
        keymesh.dask.contour(da.zeros((4, 4, 4), dtype=np.complex128, chunks=2), 0.0)
    with pytest.raises(keymesh.Error, match="not a label map"):
        keymesh.dask.contour_labels(vol)
    with pytest.raises(ValueError, match="method"):
        keymesh.dask.contour_labels(da.zeros((4, 4, 4), dtype=np.uint8, chunks=2), method="marching")


# One-sample chunks of a (13, 11, 12) volume: 1716 chunks, every edge across
# two of them, more than 1000 points still; those of (23, 19, 21) were 9177
# chunks, whose Dask bookkeeping took 13 s a call (a quarter of `make test`'s
# Python module test), for the same check.
@pytest.mark.parametrize("order", ["C", "F"])
@pytest.mark.parametrize("shape, chunks", [((23, 19, 21), ((5, 1, 10, 7), (19,), (2, 9, 10))), ((13, 11, 12), 1),
                                           ((23, 19, 21), (23, 19, 21))])
def test_history_equals_in_memory(order, shape, chunks):
    """history=True: history_key and history_t of every chunking are the
    in-memory call's (keys of the whole array, not of a chunk), and they give
    every point back through docs/HISTORY.md's formula (its origin keeps
    coordinates away from zero, where the formula's bound is looser)."""
    field = smooth_random_field(shape, seed=5)
    vol = np.asfortranarray(field) if order == "F" else np.ascontiguousarray(field)
    iso = [0.0, 0.05]
    kw = dict(spacing=(0.7, 1.1, 1.3), origin=(3.0, 2.5, 2.0), normals="none", history=True)
    want = keymesh.contour(vol, iso, **kw)
    got = keymesh.dask.contour(da.from_array(field, chunks=chunks), iso, order=order, **kw)
    assert want.n_points > 1000
    assert_same(got, want)
    key, t = got.point_data["history_key"], got.point_data["history_t"]
    assert key.dtype == np.uint64 and t.dtype == np.float32
    n = np.prod(vol.shape)
    edge = key % (3 * n)
    point, axis = edge // 3, edge % 3
    ijk = np.stack(np.unravel_index(point, vol.shape, order="F"), axis=1).astype(np.float64)
    ijk[np.arange(len(ijk)), axis] += t.astype(np.float64)
    again = (np.array([3.0, 2.5, 2.0]) + np.array([0.7, 1.1, 1.3]) * ijk).astype(np.float32)
    assert np.array_equal(again, got.points)


def test_history_refused_with_coarsen():
    vol = sphere_field((9, 9, 9), center=(4.2, 4.1, 3.9))
    with pytest.raises(ValueError, match="history with coarsen"):
        keymesh.dask.contour(da.from_array(vol, chunks=4), 3.5, coarsen=True, history=True)
