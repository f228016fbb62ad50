"""Arrays returned by keymesh own their memory: they outlive the Mesh, the
Volume and the module's temporaries."""
import gc

import numpy as np

import keymesh
from conftest import sphere_field


def test_points_survive_the_mesh():
    f = sphere_field()
    mesh = keymesh.contour(f, 12.37)
    points, cells, normals = mesh.points, mesh.cells, mesh.point_data["Normals"]
    expected = (points.copy(), cells.copy(), normals.copy())
    del mesh
    gc.collect()
    # Allocate and free a lot to reuse any freed memory.
    for _ in range(3):
        keymesh.contour(f * 1.5, 9.1)
        junk = [np.full(1 << 16, 7.0) for _ in range(20)]
        del junk
    gc.collect()
    assert np.array_equal(points, expected[0]) and np.array_equal(cells, expected[1])
    assert np.array_equal(normals, expected[2])
    assert points.flags.owndata is False and points.base is not None  # the capsule owns the buffer
    points[0, 0] = 123.0  # writable
    assert points[0, 0] == 123.0


def test_volume_view_keeps_the_volume_alive():
    vol = keymesh.Volume(np.arange(24, dtype=np.int16).reshape(2, 3, 4))
    view = vol.array
    del vol
    gc.collect()
    _ = [np.zeros(1 << 16) for _ in range(10)]
    assert np.array_equal(view, np.arange(24, dtype=np.int16).reshape(2, 3, 4))


def test_key_reduce_outputs_survive():
    keys = np.array([3, 1, 3, 2], np.uint64)
    out = keymesh.key_reduce(keys, np.array([1.0, 2.0, 3.0, 4.0]))
    del keys
    gc.collect()
    assert out[0].tolist() == [1, 2, 3] and out[1].tolist() == [2.0, 4.0, 2.0]


def test_input_array_not_modified():
    f = sphere_field().astype(np.float32)
    before = f.copy()
    keymesh.contour(f, 12.37)
    assert np.array_equal(f, before)
