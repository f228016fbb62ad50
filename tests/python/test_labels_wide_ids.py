"""keymesh.contour_labels (and keymesh.dask.contour_labels) on the wide integer
label maps of connectomics segmentations: uint32, int64 and uint64 arrays give
the mesh of the same volume relabelled to uint8 ids, with boundary_labels and
label mapped through the ids (an increasing map, so the labels' order is the
same); ids float32 cannot hold (past 2^24) and uint64 ids past 2^63 - 1 are
refused by name (docs/decisions/wide-label-types.md)."""
import numpy as np
import pytest

import keymesh

from conftest import smooth_random_field


def label_map(shape=(20, 17, 15), seed=5):
    """Four labels and background from a smooth random field's bands."""
    f = smooth_random_field(shape, seed=seed)
    return np.digitize(f, np.quantile(f, [0.3, 0.5, 0.7, 0.85])).astype(np.uint8)


# The ids of values 0..4 (background first), increasing; |id| <= 2^24.
IDS = {
    np.uint32: [0, 7, 65536, 9_999_999, 2**24],
    np.uint64: [0, 1, 70000, 16_000_001, 2**24],
    np.int64: [-(2**24), -16_000_000, -5, 123_456, 2**24],
}


def relabelled(vol, dtype):
    return np.array(IDS[dtype], dtype=dtype)[vol]


def assert_mapped(small, wide, ids):
    assert np.array_equal(small.points, wide.points)
    assert np.array_equal(small.cells, wide.cells)
    assert list(small.cell_data) == list(wide.cell_data)
    table = np.array(ids, np.float64)
    for name, values in small.cell_data.items():
        assert wide.cell_data[name].dtype == np.float32
        assert np.array_equal(table[values.astype(np.int64)], wide.cell_data[name].astype(np.float64)), name


@pytest.mark.parametrize("dtype", [np.uint32, np.uint64, np.int64])
@pytest.mark.parametrize("options", [dict(), dict(method="discrete_marching_cubes", per_label=True),
                                     dict(per_label=True, coarsen=True)])
def test_wide_dtypes_equal_uint8_relabelled(dtype, options):
    vol = label_map()
    ids = IDS[dtype]
    small = keymesh.contour_labels(vol, **options)
    wide = keymesh.contour_labels(relabelled(vol, dtype), background=ids[0], **options)
    assert small.n_cells > 500
    assert_mapped(small, wide, ids)
    # The selection by wide ids: the same surfaces as by the small ones.
    picked = keymesh.contour_labels(relabelled(vol, dtype), background=ids[0], labels=[ids[2], ids[4]], **options)
    assert_mapped(keymesh.contour_labels(vol, labels=[2, 4], **options), picked, ids)


def test_fortran_and_byte_swapped_arrays():
    vol = label_map(seed=8)
    want = keymesh.contour_labels(relabelled(vol, np.uint64))
    assert np.array_equal(keymesh.contour_labels(np.asfortranarray(relabelled(vol, np.uint64))).points, want.points)
    swapped = relabelled(vol, np.uint64).astype(">u8")
    got = keymesh.contour_labels(swapped)
    assert np.array_equal(got.points, want.points) and np.array_equal(got.cells, want.cells)


def test_refusals_name_the_label():
    vol = label_map()
    big = np.array([0, 1, 2, 3, 4_000_000_000], np.uint32)[vol]
    with pytest.raises(keymesh.Error, match="label 4000000000 is past 2\\^24"):
        keymesh.contour_labels(big)
    past = np.array([0, 1, 2, 3, 2**63 + 11], np.uint64)[vol]
    with pytest.raises(keymesh.Error, match="label 9223372036854775819 is past 2\\^63 - 1"):
        keymesh.contour_labels(past)
    # contour keeps refusing them (TypeError, as before), pointing at contour_labels.
    with pytest.raises(TypeError, match="uint64.*contour_labels"):
        keymesh.contour(relabelled(vol, np.uint64), 0.5)


def test_distinct_label_limit_states_the_count():
    """A volume of 67,032 distinct uint32 ids (every voxel its own label) is
    refused by the 65,536-label limit, stating the true count (67,033 with
    the background) and the limit; the interpreter lives on."""
    shape = (42, 42, 38)
    many = (np.arange(np.prod(shape), dtype=np.uint32) * 200 + 5).reshape(shape)  # ids under 2^24
    want = "^labels: the volume holds 67033 distinct labels \\(background included\\), more than the supported 65536$"
    with pytest.raises(keymesh.Error, match=want):
        keymesh.contour_labels(many, smoothing_iterations=0)
    assert keymesh.contour_labels(label_map()).n_cells > 500


def test_dask_contour_labels_wide():
    da = pytest.importorskip("dask.array")
    import keymesh.dask
    vol = label_map()
    for dtype in (np.uint32, np.int64, np.uint64):
        wide = relabelled(vol, dtype)
        want = keymesh.contour_labels(wide, background=IDS[dtype][0])
        got = keymesh.dask.contour_labels(da.from_array(wide, chunks=(7, 8, (4, 1, 10))), background=IDS[dtype][0])
        assert np.array_equal(got.points, want.points) and np.array_equal(got.cells, want.cells)
        for name in want.cell_data:
            assert np.array_equal(got.cell_data[name], want.cell_data[name]), name


def _files(top):
    import os
    return sorted(os.path.relpath(os.path.join(r, f), top) for r, _, fs in os.walk(top) for f in fs)


def test_labels_precomputed_wide_ids_exact(tmp_path):
    """Neuroglancer output keeps 64-bit segment ids exact (past 2^24 too), in
    memory and through keymesh.dask: each segment's manifest and fragments
    are those of the same volume relabelled to uint8, and the Dask run's
    directory is the in-memory one's, byte for byte."""
    import filecmp
    vol = label_map()
    ids = [0, 4_000_000_000, 2**40 + 3, 2**62 + 1, 2**63 - 1]
    wide = np.array(ids, np.uint64)[vol]
    grid = dict(lods=2, chunk_shape=(8, 8, 8), smooth=2)
    small = keymesh.labels_precomputed(vol, str(tmp_path / "small"), **grid)
    report = keymesh.labels_precomputed(wide, str(tmp_path / "wide"), **grid)
    assert sorted(report["segments"]) == sorted(ids[v] for v in small["segments"])
    for v in small["segments"]:
        for suffix in ("", ".index"):
            assert filecmp.cmp(tmp_path / "small" / f"{v}{suffix}", tmp_path / "wide" / f"{ids[v]}{suffix}",
                               shallow=False), (v, suffix)
    da = pytest.importorskip("dask.array")
    kdask = pytest.importorskip("keymesh.dask")
    kdask.labels_precomputed(da.from_array(wide, chunks=(7, 8, (4, 1, 10))), str(tmp_path / "dask"), **grid)
    names = _files(tmp_path / "wide")
    assert names == _files(tmp_path / "dask")
    for name in names:
        assert filecmp.cmp(tmp_path / "wide" / name, tmp_path / "dask" / name, shallow=False), name
