"""keymesh.key_reduce against a numpy reference (np.unique + ufunc.at)."""
import numpy as np
import pytest

import keymesh

UFUNC = {"sum": np.add, "min": np.minimum, "max": np.maximum}


def reference(keys, values, op):
    uniq, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
    v = np.asarray(values, dtype=np.float64)
    if op in ("sum", "mean"):
        out = np.zeros((len(uniq),) + v.shape[1:])
        np.add.at(out, inverse, v)
        if op == "mean":
            out /= counts.reshape((-1,) + (1,) * (v.ndim - 1))
    else:
        out = np.full((len(uniq),) + v.shape[1:], np.inf if op == "min" else -np.inf)
        UFUNC[op].at(out, inverse, v)
    return uniq, out, inverse, counts


def check(keys, values, op):
    uniq, reduced, index_map, counts = keymesh.key_reduce(keys, values, op)
    r_uniq, r_out, r_inverse, r_counts = reference(keys, values, op)
    if np.asarray(keys).dtype in (np.uint32, np.uint64, np.int64):
        assert uniq.dtype == np.asarray(keys).dtype
    assert reduced.dtype == np.asarray(values).dtype and reduced.shape == r_out.shape
    assert np.array_equal(uniq, r_uniq)
    assert np.array_equal(index_map, r_inverse.reshape(-1))
    assert np.array_equal(counts, r_counts)
    rtol = 1e-6 if reduced.dtype == np.float32 else 1e-12
    np.testing.assert_allclose(reduced, r_out.astype(reduced.dtype), rtol=rtol, atol=rtol)
    if len(keys):
        assert np.array_equal(uniq[index_map], keys)


@pytest.mark.parametrize("op", ["mean", "sum", "min", "max"])
@pytest.mark.parametrize("key_dtype", [np.uint32, np.uint64, np.int64])
@pytest.mark.parametrize("value_dtype", [np.float32, np.float64])
def test_random_keys(op, key_dtype, value_dtype):
    rng = np.random.default_rng(11)
    keys = rng.integers(0, 5000, size=20000).astype(key_dtype)
    check(keys, rng.standard_normal(20000).astype(value_dtype), op)
    check(keys, rng.standard_normal((20000, 3)).astype(value_dtype), op)


@pytest.mark.parametrize("op", ["mean", "sum", "min", "max"])
def test_all_equal_keys(op):
    keys = np.full(1000, 42, np.uint32)
    values = np.random.default_rng(1).random((1000, 2))
    check(keys, values, op)


@pytest.mark.parametrize("op", ["mean", "sum", "min", "max"])
def test_empty(op):
    uniq, reduced, index_map, counts = keymesh.key_reduce(np.zeros(0, np.uint64), np.zeros(0), op)
    assert uniq.shape == (0,) and reduced.shape == (0,) and index_map.shape == (0,) and counts.shape == (0,)
    uniq, reduced, _, _ = keymesh.key_reduce(np.zeros(0, np.uint32), np.zeros((0, 3), np.float32), op)
    assert reduced.shape == (0, 3)


def test_top_of_uint64_range():
    top = np.iinfo(np.uint64).max
    keys = np.array([top, 0, top, 1 << 63, top - 1, 0], dtype=np.uint64)
    values = np.arange(6, dtype=np.float64)
    for op in ("mean", "sum", "min", "max"):
        check(keys, values, op)
    uniq, _, _, counts = keymesh.key_reduce(keys, values)
    assert uniq[-1] == top and counts[-1] == 2


def test_python_lists_and_narrow_ints():
    uniq, reduced, index_map, counts = keymesh.key_reduce([3, 1, 3], np.array([1.0, 2.0, 5.0]), "sum")
    assert uniq.tolist() == [1, 3] and reduced.tolist() == [2.0, 6.0] and counts.tolist() == [1, 2]
    check(np.array([5, 2, 5], np.uint16), np.array([1.0, 2.0, 3.0]), "mean")


def test_deterministic_across_threads():
    rng = np.random.default_rng(5)
    keys = rng.integers(0, 1 << 40, size=50000).astype(np.uint64) % 3000
    values = rng.standard_normal((50000, 2)).astype(np.float32)
    ref = keymesh.key_reduce(keys, values, "mean", threads=1)
    for t in (2, 3, 0):
        out = keymesh.key_reduce(keys, values, "mean", threads=t)
        for a, b in zip(ref, out):
            assert np.array_equal(a, b)


def test_nan_propagates_in_min_max():
    keys = np.array([0, 0, 1], np.uint32)
    values = np.array([np.nan, 1.0, 2.0])
    assert np.isnan(keymesh.key_reduce(keys, values, "min")[1][0])
    assert np.isnan(keymesh.key_reduce(keys, values, "max")[1][0])
