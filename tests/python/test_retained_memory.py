"""A freed output's large arrays are kept for the next call (core/retained_blocks):
the next contour reuses them and still returns exactly the first call's mesh;
release_memory() gives them back; KEYMESH_RETAINED_MEMORY_MB=0 keeps nothing."""
import os
import subprocess
import sys

import numpy as np

import keymesh


def gyroid_like(n=128):
    """A surface through the whole cube: about 7 MB of points, 14 MB of triangles."""
    g = np.mgrid[0:n, 0:n, 0:n].astype(np.float32)
    return (np.sin(0.5 * g[0]) + np.sin(0.5 * g[1]) + np.sin(0.5 * g[2])).astype(np.float32)


def test_the_next_call_reuses_the_freed_arrays_and_gives_the_same_mesh():
    v = gyroid_like()
    keymesh.release_memory()
    first = keymesh.contour(v, 0.1, normals="none", scalars=False, threads=2)
    points, cells = first.points.copy(), first.cells.copy()
    assert points.nbytes >= 4 << 20 and cells.nbytes >= 4 << 20  # both large enough to be kept
    del first
    kept = keymesh.retained_memory()
    assert kept["kept_blocks"] >= 2 and kept["kept_bytes"] >= points.nbytes + cells.nbytes
    again = keymesh.contour(v, 0.1, normals="none", scalars=False, threads=2)
    after = keymesh.retained_memory()
    assert after["reused"] >= kept["reused"] + 2
    assert np.array_equal(again.points, points) and np.array_equal(again.cells, cells)
    del again
    released = keymesh.release_memory()
    assert released >= points.nbytes + cells.nbytes
    assert keymesh.retained_memory()["kept_bytes"] == 0


def test_a_limit_of_zero_keeps_nothing():
    code = ("import numpy as np, keymesh\n"
            "g = np.mgrid[0:128, 0:128, 0:128].astype(np.float32) - 63.5\n"
            "m = keymesh.contour(np.sqrt((g ** 2).sum(axis=0)), 0.1, normals='none', scalars=False)\n"
            "del m\n"
            "r = keymesh.retained_memory()\n"
            "print(r['kept_bytes'], r['limit_bytes'])\n")
    env = dict(os.environ, KEYMESH_RETAINED_MEMORY_MB="0")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["0", "0"]
