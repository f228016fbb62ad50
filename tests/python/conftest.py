"""Shared volumes and helpers of the Python module's tests (run by ctest via
python/run_tests.py with PYTHONPATH=<build>/python)."""
import numpy as np
import pytest

import keymesh


def sphere_field(shape=(41, 37, 45), center=(20.3, 17.9, 22.6)):
    """Distance of every sample from `center` (axis 0 = x): float64."""
    i, j, k = np.indices(shape, dtype=np.float64)
    return np.sqrt((i - center[0]) ** 2 + (j - center[1]) ** 2 + (k - center[2]) ** 2)


def smooth_random_field(shape=(34, 30, 38), seed=7, passes=4):
    """White noise smoothed by repeated 3-point box filters along each axis
    (numpy only): a field with many small blobs and saddles."""
    f = np.random.default_rng(seed).standard_normal(shape)
    for _ in range(passes):
        for axis in range(3):
            f = (np.roll(f, 1, axis) + f + np.roll(f, -1, axis)) / 3.0
    return f


def noise_field(shape=(24, 22, 20), seed=3):
    """Plain white noise: every ambiguous marching-cubes configuration occurs."""
    return np.random.default_rng(seed).standard_normal(shape)


def history_positions(ijk, axis, t, origin, spacing):
    """Points given back from their history (docs/HISTORY.md): float32(origin
    + spacing * u), u the sample coordinates ijk (n, 3) plus t (n,) along
    each point's edge axis (n,)."""
    u = np.asarray(ijk).astype(np.float64)
    u[np.arange(len(u)), axis] += np.asarray(t).astype(np.float64)
    return (np.asarray(origin, np.float64) + np.asarray(spacing, np.float64) * u).astype(np.float32)


def match_points(a, b, tol=1e-4):
    """The permutation p with a[i] ~ b[p[i]] (every point within tol of
    exactly one partner); asserts that the two point sets are equal."""
    from scipy.spatial import cKDTree

    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    assert a.shape == b.shape, (a.shape, b.shape)
    dist, p = cKDTree(b).query(a)
    assert dist.max(initial=0.0) <= tol, dist.max()
    assert len(np.unique(p)) == len(p), "two points matched the same partner"
    return p


def oriented_faces(cells):
    """Triangles as a set of tuples, each rotated to start at its smallest id
    (orientation kept)."""
    c = np.asarray(cells, dtype=np.int64)
    r = np.argmin(c, axis=1)
    rolled = np.stack([c[np.arange(len(c)), (r + s) % 3] for s in range(3)], axis=1)
    return set(map(tuple, rolled.tolist()))


@pytest.fixture(scope="session")
def sphere():
    return sphere_field()


@pytest.fixture(scope="session")
def smooth():
    return smooth_random_field()


@pytest.fixture(scope="session")
def noise():
    return noise_field()


@pytest.fixture
def km():
    return keymesh
