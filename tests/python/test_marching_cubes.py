"""keymesh.marching_cubes against skimage.measure.marching_cubes, methods
'lewiner' (Marching Cubes 33, the default of both) and 'lorensen'.

The volumes here are new to the project's tests: a gyroid, a sum of random
Gaussian blobs, an anisotropic integer-valued ellipsoid (samples equal to the
level: the strict 'value > level' rule and degenerate triangles), and a
random uint8 volume. With scikit-image's case table (found when scikit-image
is installed) the four arrays must be scikit-image's exactly: same order,
same bits (normals within 1e-5 where float32 sums could round differently;
they have come out equal). 'lewiner' needs scikit-image's tables; plain
white noise (every ambiguous case, every face and interior test, many
centre points) is its hardest check.
With keymesh's own table the points and values stay exact and the polygons
the same; only diagonals (and so some normals) move.
"""
import numpy as np
import pytest

import keymesh
from keymesh import _skimage_compat
from conftest import match_points

measure = pytest.importorskip("skimage.measure")


def gyroid(shape=(29, 33, 31)):
    i, j, k = np.indices(shape, dtype=np.float64)
    x, y, z = i * 0.37, j * 0.29, k * 0.41
    return np.sin(x) * np.cos(y) + np.sin(y) * np.cos(z) + np.sin(z) * np.cos(x)


def blobs(shape=(36, 27, 32), seed=11, count=9):
    rng = np.random.default_rng(seed)
    idx = np.indices(shape, dtype=np.float64)
    f = np.zeros(shape)
    for _ in range(count):
        c = rng.uniform(0, 1, 3) * np.array(shape)
        r = rng.uniform(2.5, 6.0)
        f += np.exp(-sum((idx[a] - c[a]) ** 2 for a in range(3)) / (2 * r * r))
    return f.astype(np.float32)


def integer_ellipsoid(shape=(25, 30, 21)):
    i, j, k = np.indices(shape, dtype=np.float64)
    d = ((i - 12) / 1.0) ** 2 + ((j - 14.5) / 1.3) ** 2 + ((k - 10) / 0.8) ** 2
    return np.floor(d).astype(np.int16)


def random_uint8(shape=(19, 23, 17), seed=5):
    return np.random.default_rng(seed).integers(0, 256, shape, dtype=np.uint8)


VOLUMES = {
    "gyroid": (gyroid, 0.173),
    "blobs": (blobs, 0.41),
    "ellipsoid": (integer_ellipsoid, 81.0),   # many samples equal the level
    "uint8": (random_uint8, 128.0),
}

need_table = pytest.mark.skipif(not _skimage_compat.uses_skimage_table(),
                                reason="scikit-image's case table is not importable")
need_mc33 = pytest.mark.skipif(_skimage_compat._mc33_tables() is None,
                               reason="scikit-image's Marching Cubes 33 tables are not importable")
METHODS = ["lewiner", "lorensen"]


def assert_same_as_skimage(v, level, **kwargs):
    """keymesh.marching_cubes and scikit-image's on the same arguments."""
    assert_same(keymesh.marching_cubes(v, level, **kwargs), measure.marching_cubes(v, level, **kwargs))


def assert_same(ours, theirs, exact_normals=False):
    names = ("verts", "faces", "normals", "values")
    for name, a, b in zip(names, ours, theirs):
        assert a.dtype == b.dtype, (name, a.dtype, b.dtype)
        assert a.shape == b.shape, (name, a.shape, b.shape)
    assert np.array_equal(ours[0], theirs[0]), np.abs(ours[0] - theirs[0]).max()
    assert np.array_equal(ours[1], theirs[1])
    assert np.abs(ours[2] - theirs[2]).max(initial=0) <= (0 if exact_normals else 1e-5)
    assert np.array_equal(ours[3], theirs[3])


@need_table
@need_mc33
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", sorted(VOLUMES))
@pytest.mark.parametrize("spacing", [(1.0, 1.0, 1.0), (0.5, 1.25, 2.0)])
@pytest.mark.parametrize("direction", ["descent", "ascent"])
def test_identical_to_skimage(name, spacing, direction, method):
    make, level = VOLUMES[name]
    v = make()
    assert_same_as_skimage(v, level, spacing=spacing, gradient_direction=direction, method=method)


@need_table
@need_mc33
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", ["gyroid", "blobs", "uint8"])
@pytest.mark.parametrize("step", [2, 3, 5])
def test_step_size(name, step, method):
    make, level = VOLUMES[name]
    v = make()
    assert_same_as_skimage(v, level, step_size=step, method=method)


@need_table
@need_mc33
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", ["gyroid", "blobs", "ellipsoid"])
@pytest.mark.parametrize("step", [1, 2])
def test_mask(name, step, method):
    make, level = VOLUMES[name]
    v = make()
    rng = np.random.default_rng(17)
    mask = rng.random(v.shape) < 0.6
    mask[: v.shape[0] // 3] = False          # an open cut as well as random holes
    assert_same_as_skimage(v, level, mask=mask, step_size=step, method=method)


@need_table
@need_mc33
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", ["ellipsoid", "uint8", "gyroid"])
def test_level_none_and_no_degenerate(name, method):
    make, level = VOLUMES[name]
    v = make()
    assert_same(keymesh.marching_cubes(v, method=method), measure.marching_cubes(v, method=method))
    assert_same_as_skimage(v, level, spacing=(1, 2, 3), allow_degenerate=False, method=method)


@pytest.mark.parametrize("name", ["gyroid", "blobs"])  # no sample equals the level: points are distinct
def test_keymesh_table_same_points_values_and_polygons(name, monkeypatch):
    """Without scikit-image's table: the points (matched by position) and
    their values are the same, as are the face count and the surface's
    topology; only the diagonals inside cubes may differ."""
    make, level = VOLUMES[name]
    v = make()
    theirs = measure.marching_cubes(v, level, method="lorensen")
    monkeypatch.setattr(_skimage_compat, "_TABLE_CACHE", [None])
    verts, faces, normals, values = keymesh.marching_cubes(v, level, method="lorensen")
    p = match_points(verts, theirs[0], tol=0)
    assert np.array_equal(values, theirs[3][p])
    assert faces.shape == theirs[1].shape
    ours_check = keymesh.check(keymesh.Mesh(verts, faces))
    theirs_check = keymesh.check(keymesh.Mesh(theirs[0], theirs[1]))
    for key in ("edges", "boundary_edges", "nonmanifold_edges", "euler_characteristic", "components"):
        assert ours_check[key] == theirs_check[key], key
    # the normals still point the same way (to lower values)
    assert np.all(np.einsum("ij,ij->i", normals, theirs[2][p]) > 0.5)


@pytest.mark.parametrize("name", sorted(VOLUMES))
def test_welded_and_thread_independent(name):
    make, level = VOLUMES[name]
    v = make()
    one = keymesh.marching_cubes(v, level, threads=1, method="lorensen")
    two = keymesh.marching_cubes(v, level, threads=2, method="lorensen")
    for a, b in zip(one, two):
        assert np.array_equal(a, b)
    verts, faces = one[0], one[1]
    if name in ("gyroid", "blobs"):  # no sample equals the level: no two points coincide
        assert len(np.unique(verts, axis=0)) == len(verts)
    assert faces.min() == 0 and faces.max() == len(verts) - 1
    # one point per grid edge whose samples straddle the level (value > level inside)
    inside = np.asarray(v, np.float32) > level
    crossings = sum(int(np.count_nonzero(np.diff(inside, axis=a))) for a in range(3))
    assert len(verts) == crossings


def test_faces_face_lower_values_with_descent():
    """'descent' (the default) winds triangles so that their right-hand
    normal points to higher values: on a ball of high values inside, the
    right-hand normals point inwards, and the returned normals outwards."""
    i, j, k = np.indices((30, 30, 30), dtype=np.float64)
    ball = 20.0 - np.sqrt((i - 14.6) ** 2 + (j - 15.2) ** 2 + (k - 14.1) ** 2)
    verts, faces, normals, _ = keymesh.marching_cubes(ball, 10.0, method="lorensen")
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    face_n = np.cross(b - a, c - a)
    outward = (a + b + c) / 3 - np.array([14.6, 15.2, 14.1])
    assert np.all(np.einsum("ij,ij->i", face_n, outward) < 0)
    radial = verts - np.array([14.6, 15.2, 14.1])
    assert np.all(np.einsum("ij,ij->i", normals, radial) > 0)


BAD_ARGUMENTS = [
    ("2-D volume", lambda v: ((v[0],), {})),
    ("list volume", lambda v: ((v.tolist(), 0.2), {})),
    ("too small", lambda v: ((v[:1], 0.2), {})),
    ("level above", lambda v: ((v, 99.0), {})),
    ("level below", lambda v: ((v, -99.0), {})),
    ("level text", lambda v: ((v, "abc"), {})),
    ("level object", lambda v: ((v, object()), {})),
    ("spacing 2", lambda v: ((v, 0.2), {"spacing": (1, 1)})),
    ("spacing number", lambda v: ((v, 0.2), {"spacing": 1.0})),
    ("step 0", lambda v: ((v, 0.2), {"step_size": 0})),
    ("step text", lambda v: ((v, 0.2), {"step_size": "x"})),
    ("mask shape", lambda v: ((v, 0.2), {"mask": np.ones((2, 2, 2), bool)})),
    ("mask list", lambda v: ((v, 0.2), {"mask": [[[True]]]})),
    ("direction", lambda v: ((v, 0.2), {"gradient_direction": "up"})),
    ("method", lambda v: ((v, 0.2), {"method": "cubes"})),
    ("no surface", lambda v: ((v, float(np.float32(v).max())), {})),
]


def outcome(function, args, kwargs):
    """The exception type a call raises, or its result."""
    try:
        return function(*args, **kwargs)
    except Exception as e:  # noqa: BLE001 - the type is what is compared
        return type(e)


def ones_mask(dtype):
    return lambda v: ((v, 0.2), {"mask": np.ones(v.shape, dtype)})


# scikit-image 0.19 hands the mask to Cython as a 1-byte buffer: any 1-byte
# dtype passes (bytes taken as they are), wider ones raise ValueError; a bad
# gradient_direction is looked at only once a surface was found.
MASK_AND_ORDER = [
    ("mask float64", ones_mask(np.float64)),
    ("mask float32", ones_mask(np.float32)),
    ("mask int64", ones_mask(np.int64)),
    ("mask int16", ones_mask(np.int16)),
    ("mask object", ones_mask(object)),
    ("mask int8", lambda v: ((v, 0.2), {"mask": (np.arange(v.size).reshape(v.shape) % 3).astype(np.int8)})),
    ("mask uint8", lambda v: ((v, 0.2), {"mask": (np.arange(v.size).reshape(v.shape) % 5 == 1).astype(np.uint8) * 7})),
    ("mask bool strided", lambda v: ((v, 0.2), {"mask": np.ones(v.shape[::-1], bool).T})),
    ("mask float, bad direction", lambda v: ((v, 0.2), {"mask": np.ones(v.shape), "gradient_direction": "up"})),
    ("no surface, bad direction", lambda v: ((v, float(np.float32(v).max())), {"gradient_direction": "up"})),
    ("no surface, direction None", lambda v: ((v, float(np.float32(v).max())), {"gradient_direction": None})),
    ("surface, direction None", lambda v: ((v, 0.2), {"gradient_direction": None})),
    ("no surface in mask, bad direction", lambda v: ((v, 0.2), {"mask": np.zeros(v.shape, bool),
                                                                "gradient_direction": "up"})),
]


def ours_and_theirs(make_args, method):
    """Both functions' outcomes (result or exception type) on a small gyroid."""
    args, kwargs = make_args(gyroid((8, 9, 10)))
    kwargs = {"method": method, **kwargs}
    return outcome(keymesh.marching_cubes, args, kwargs), outcome(measure.marching_cubes, args, kwargs)


ARGUMENTS = BAD_ARGUMENTS + MASK_AND_ORDER


@need_mc33
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("label,make_args", ARGUMENTS, ids=[b[0] for b in ARGUMENTS])
def test_arguments_as_skimage(label, make_args, method):
    """The same exception type as scikit-image, or (accepted) its result."""
    ours, theirs = ours_and_theirs(make_args, method)
    if isinstance(theirs, type):
        assert ours is theirs, (ours, theirs)
    else:
        assert not isinstance(ours, type), ours
        if _skimage_compat.uses_skimage_table():
            assert_same(ours, theirs)


OLD_LORENSEN_ARGUMENTS = [
    ("plain", lambda v: ((v, 0.2), {})),
    ("level None, spacing", lambda v: ((v,), {"spacing": (0.5, 1.0, 2.0)})),
    ("ascent", lambda v: ((v, 0.2), {"gradient_direction": "ascent"})),
    ("direction inside a word", lambda v: ((v, 0.2), {"gradient_direction": "xdescentx"})),
    ("step and degenerate ignored", lambda v: ((v, 0.2), {"step_size": 0, "allow_degenerate": False})),
    ("mask", lambda v: ((v, 0.2), {"mask": np.ones(v.shape, bool)})),
    ("mask None", lambda v: ((v, 0.2), {"mask": None})),
    ("2-D volume", lambda v: ((v[0], 0.2), {})),
    ("list volume", lambda v: ((v.tolist(), 0.2), {})),
    ("too small", lambda v: ((v[:1], 0.2), {})),
    ("too small, level above", lambda v: ((v[:1], 99.0), {})),
    ("level above", lambda v: ((v, 99.0), {})),
    ("level text", lambda v: ((v, "abc"), {})),
    ("spacing number", lambda v: ((v, 0.2), {"spacing": 1.0})),
    ("direction", lambda v: ((v, 0.2), {"gradient_direction": "up"})),
    ("direction None", lambda v: ((v, 0.2), {"gradient_direction": None})),
    ("no surface", lambda v: ((v, float(v.max())), {})),
    ("no surface, bad direction", lambda v: ((v, float(v.max())), {"gradient_direction": "up"})),
]


@pytest.mark.parametrize("label,make_args", OLD_LORENSEN_ARGUMENTS, ids=[b[0] for b in OLD_LORENSEN_ARGUMENTS])
def test_old_lorensen_method_as_skimage(label, make_args):
    """method='_lorensen' (scikit-image 0.19's old classic code) is accepted:
    the same errors, and two arrays, float64 points and int64 faces, with
    scikit-image's points (to float32 rounding: it interpolates in float64)
    and, where a cube is split the same way, its triangles with its winding."""
    ours, theirs = ours_and_theirs(make_args, "_lorensen")
    if isinstance(theirs, type):
        assert ours is theirs, (ours, theirs)
        return
    assert isinstance(ours, tuple) and len(ours) == 2, ours
    for a, b in zip(ours, theirs):
        assert a.dtype == b.dtype and a.shape[1:] == b.shape[1:], (a.dtype, b.dtype)
    p = match_points(ours[0], theirs[0], tol=1e-5)
    assert len(ours[1]) >= 0.95 * len(theirs[1])
    assert_shared_triangles_wound_alike(p[ours[1]], theirs[1])


def assert_shared_triangles_wound_alike(a, b):
    a_sets = {frozenset(t): t for t in map(tuple, a.tolist())}
    b_sets = {frozenset(t): t for t in map(tuple, b.tolist())}
    shared = a_sets.keys() & b_sets.keys()
    assert len(shared) >= 0.4 * len(b_sets)
    for key in shared:
        s, t = a_sets[key], b_sets[key]
        assert t in (s, s[1:] + s[:1], s[2:] + s[:2]), (s, t)


@pytest.mark.parametrize("name", sorted(VOLUMES))
def test_old_lorensen_points_as_skimage(name):
    make, level = VOLUMES[name]
    v = make()
    theirs = measure.marching_cubes(v, level, spacing=(1.0, 0.5, 3.0), method="_lorensen")
    ours = keymesh.marching_cubes(v, level, spacing=(1.0, 0.5, 3.0), method="_lorensen")
    assert ours[0].dtype == theirs[0].dtype and ours[1].dtype == theirs[1].dtype
    if name == "uint8":
        # scikit-image's old code also drops points that only degenerate
        # triangles used; keymesh's degenerate-face rule keeps some of them
        return
    p = match_points(ours[0], theirs[0], tol=1e-5)
    assert_shared_triangles_wound_alike(p[ours[1]], theirs[1])


def nan_volume(seed):
    v = blobs((14, 15, 13), seed=seed, count=3)
    rng = np.random.default_rng(seed)
    v.flat[rng.choice(v.size, 12, replace=False)] = np.nan
    return v


@need_table
@need_mc33
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("step", [1, 2])
def test_nan_samples_as_skimage(seed, step, method):
    """A NaN sample counts as outside (NaN > level is false); a point on an
    edge with a NaN end is NaN on all three axes and so is its normal (and
    every normal that took a NaN gradient); values skip the NaN."""
    v = nan_volume(seed)
    level = 0.3 * float(np.nanmax(v))
    for kwargs in ({}, {"spacing": (0.5, 1.0, 2.0)}, {"allow_degenerate": False}):
        ours = keymesh.marching_cubes(v, level, step_size=step, method=method, **kwargs)
        theirs = measure.marching_cubes(v, level, step_size=step, method=method, **kwargs)
        nan_rows = np.isnan(theirs[0]).any(axis=1)
        assert nan_rows.any() and np.isnan(theirs[0][nan_rows]).all()
        for name, a, b in zip(("verts", "faces", "normals", "values"), ours, theirs):
            assert a.dtype == b.dtype and a.shape == b.shape, name
            assert np.array_equal(np.isnan(a), np.isnan(b)), name
        assert np.array_equal(ours[0], theirs[0], equal_nan=True)
        assert np.array_equal(ours[1], theirs[1])
        assert np.nanmax(np.abs(ours[2] - theirs[2]), initial=0) <= 1e-5
        assert np.array_equal(ours[3], theirs[3])
    # level None: the NaN mid-range finds no surface, in both
    assert outcome(keymesh.marching_cubes, (v,), {"method": method}) is RuntimeError
    assert outcome(measure.marching_cubes, (v,), {"method": method}) is RuntimeError


def noise_volumes():
    """White noise of several kinds: every case and sub-case of Marching
    Cubes 33 occurs thousands of times; integer samples put corners exactly
    on the level (the tests' epsilon branches)."""
    rng = np.random.default_rng(2026)
    yield "normal", rng.standard_normal((34, 31, 29)).astype(np.float32), 0.0
    yield "uniform float64", rng.random((30, 33, 28)), 0.5
    yield "int8 on the level", rng.integers(-2, 3, (31, 29, 33)).astype(np.int8), 0.0
    yield "int16", rng.integers(0, 4, (29, 30, 31)).astype(np.int16), 1.5


@need_mc33
@pytest.mark.parametrize("step", [1, 2])
def test_lewiner_noise_identical_to_skimage(step):
    """The default method on noise: scikit-image's four arrays, bit for bit
    (normals too), and centre points present (ambiguous cubes resolved with
    Marching Cubes 33's extra point), for any thread count."""
    for label, v, level in noise_volumes():
        theirs = measure.marching_cubes(v, level, step_size=step)
        for threads in (1, 2):
            ours = keymesh.marching_cubes(v, level, step_size=step, threads=threads)
            assert_same(ours, theirs, exact_normals=True)
        lorensen = keymesh.marching_cubes(v, level, step_size=step, method="lorensen")
        assert len(ours[0]) > len(lorensen[0]), label  # centre points were added
        mask = np.random.default_rng(3).random(v.shape) < 0.7
        assert_same(keymesh.marching_cubes(v, level, step_size=step, mask=mask, spacing=(2, 1, 0.5)),
                    measure.marching_cubes(v, level, step_size=step, mask=mask, spacing=(2, 1, 0.5)))


def test_lewiner_without_skimage_tables_is_refused(monkeypatch):
    monkeypatch.setattr(_skimage_compat, "_MC33_CACHE", [None])
    with pytest.raises(NotImplementedError, match="lewiner"):
        keymesh.marching_cubes(gyroid((8, 8, 8)), 0.1)
    assert len(keymesh.marching_cubes(gyroid((8, 8, 8)), 0.1, method="lorensen")[0]) > 0


@need_mc33
def test_lewiner_tables_are_checked():
    """Tables the decisions would read outside of are refused (InputError,
    keymesh.Error in Python), not read."""
    tables = dict(_skimage_compat._mc33_tables())
    v = np.ascontiguousarray(gyroid((8, 8, 8)), np.float32)
    for change in ("drop", "edge 13", "face 9", "config"):
        t = {k: a.copy() for k, a in tables.items()}
        if change == "drop":
            del t["TILING7_3"]
        elif change == "edge 13":
            t["TILING5"][3, 2] = 13
        elif change == "face 9":
            t["TEST10"][1, 0] = 9
        else:
            t["CASES"][5, 1] = 100
        with pytest.raises(Exception) as error:
            keymesh._keymesh.marching_cubes(v, 0.1, None, 1, None, True, 0, None, t)
        assert "marching cubes 33" in str(error.value), change
