"""Bad arguments raise Python exceptions with clear messages, never crash."""
import numpy as np
import pytest

import keymesh

VOL = np.random.default_rng(0).random((5, 6, 7)).astype(np.float32)


@pytest.mark.parametrize("shape", [(5,), (5, 6), (2, 3, 4, 5)])
def test_contour_wrong_ndim(shape):
    with pytest.raises(ValueError, match="3-D"):
        keymesh.contour(np.zeros(shape, np.float32), 0.5)


@pytest.mark.parametrize("dtype", ["bool", "uint32", "int64", "uint64", "float16", "complex64"])
def test_contour_unsupported_dtype(dtype):
    with pytest.raises(TypeError, match=np.dtype(dtype).name):
        keymesh.contour(np.zeros((3, 3, 3), dtype), 0.5)


def test_contour_object_and_string_volumes():
    with pytest.raises(TypeError):
        keymesh.contour(np.zeros((3, 3, 3), object), 0.5)
    with pytest.raises((TypeError, ValueError)):
        keymesh.contour("not a volume", 0.5)


@pytest.mark.parametrize("iso", [float("nan"), float("inf"), [0.5, float("nan")]])
def test_contour_non_finite_iso(iso):
    with pytest.raises(ValueError, match="finite"):
        keymesh.contour(VOL, iso)


def test_contour_bad_iso_type_and_empty():
    with pytest.raises(TypeError, match="iso"):
        keymesh.contour(VOL, "half")
    with pytest.raises(ValueError, match="isovalue"):
        keymesh.contour(VOL, [])


def test_contour_bad_options():
    with pytest.raises(ValueError, match="threads"):
        keymesh.contour(VOL, 0.5, threads=-1)
    with pytest.raises(ValueError, match="normals"):
        keymesh.contour(VOL, 0.5, normals="outward")
    with pytest.raises(ValueError, match="weld"):
        keymesh.contour(VOL, 0.5, weld="glue")
    with pytest.raises(ValueError, match="spacing"):
        keymesh.contour(VOL, 0.5, spacing=(1, 2))
    with pytest.raises(TypeError, match="spacing"):
        keymesh.contour(VOL, 0.5, spacing="abc")


def test_contour_too_small_grid_is_a_keymesh_error():
    with pytest.raises(keymesh.Error, match="at least 2"):
        keymesh.contour(np.zeros((1, 4, 4), np.float32), 0.5)
    assert issubclass(keymesh.Error, ValueError) and issubclass(keymesh.LimitError, keymesh.Error)


def test_key_reduce_bad_arguments():
    k = np.arange(4, dtype=np.uint32)
    v = np.ones(4)
    with pytest.raises(ValueError, match="op"):
        keymesh.key_reduce(k, v, "median")
    with pytest.raises(ValueError, match="non-negative"):
        keymesh.key_reduce(np.array([1, -2, 3, 4]), v)
    with pytest.raises(ValueError, match="rows"):
        keymesh.key_reduce(k, np.ones(5))
    with pytest.raises(ValueError, match="1-D"):
        keymesh.key_reduce(k.reshape(2, 2), v)
    with pytest.raises(ValueError, match="1-D or 2-D"):
        keymesh.key_reduce(k, np.ones((4, 1, 1)))
    with pytest.raises(TypeError, match="float32 or float64"):
        keymesh.key_reduce(k, np.ones(4, np.int32))
    with pytest.raises(TypeError, match="float64"):
        keymesh.key_reduce(np.ones(4), v)
    with pytest.raises(ValueError, match="threads"):
        keymesh.key_reduce(k, v, threads=-3)


def test_check_and_write_bad_meshes(tmp_path):
    pts = np.zeros((3, 3), np.float32)
    with pytest.raises(ValueError, match="refers to point 7"):
        keymesh.check(keymesh.Mesh(pts, np.array([[0, 1, 7]])))
    with pytest.raises(ValueError, match="refers to point -1"):
        keymesh.check(keymesh.Mesh(pts, np.array([[0, 1, -1]])))
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        keymesh.check(keymesh.Mesh(np.zeros((3, 2)), np.array([[0, 1, 2]])))
    with pytest.raises(TypeError, match="integers"):
        keymesh.check(keymesh.Mesh(pts, np.array([[0.0, 1.0, 2.0]])))
    with pytest.raises(ValueError, match="rows"):
        keymesh.write(keymesh.Mesh(pts, np.array([[0, 1, 2]]), {"f": np.ones(2)}), tmp_path / "m.ply")
    with pytest.raises(keymesh.Error, match="unknown mesh file extension"):
        keymesh.write(keymesh.Mesh(pts, np.array([[0, 1, 2]])), tmp_path / "m.xyz")
    with pytest.raises(TypeError):
        keymesh.write(42, tmp_path / "m.ply")


def test_read_errors(tmp_path):
    with pytest.raises(keymesh.Error, match="missing.vtp"):
        keymesh.read(tmp_path / "missing.vtp")
    bad = tmp_path / "bad.vti"
    bad.write_text("not xml at all")
    with pytest.raises(keymesh.Error, match="bad.vti"):
        keymesh.read(bad)
    with pytest.raises(ValueError, match="dims"):
        keymesh.read(tmp_path / "v.raw", dtype="float32")
    # .glb is written, not read: said as the command says it, not "not a volume" (issue 33)
    glb = tmp_path / "m.glb"
    keymesh.write(keymesh.Mesh(np.eye(3, dtype=np.float32), np.array([[0, 1, 2]])), glb)
    with pytest.raises(keymesh.Error, match=r"unknown mesh file extension '\.glb' .*\.glb to write"):
        keymesh.read(glb)
