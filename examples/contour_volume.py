"""Contour a numpy volume and save it.

    numpy array (axis 0 = x)   ->   keymesh.contour: one point per grid   ->   blob.ply, blob.vtp
    of two overlapping balls        edge that crosses the isovalue,            (keymesh.write picks
                                    welded by the edge's key                   the format by extension)

Checks: the points are exactly the crossed grid edges (counted here with numpy), the surface is
one closed 2-manifold sphere (keymesh.check), and each file reads back with the same arrays.
Run: PYTHONPATH=build/python /usr/bin/python3 examples/contour_volume.py [OUTPUT_FOLDER]
"""
import os
import sys

import numpy as np

import keymesh

# Two overlapping balls: the larger of two "closeness" fields, on a 64^3 grid of 0.5 mm voxels.
i, j, k = np.indices((64, 64, 64), dtype=np.float32)
ball_a = 20.0 - np.sqrt((i - 26) ** 2 + (j - 30) ** 2 + (k - 32) ** 2)
ball_b = 16.0 - np.sqrt((i - 40) ** 2 + (j - 34) ** 2 + (k - 30) ** 2)
volume = np.maximum(ball_a, ball_b)
iso = 0.5

mesh = keymesh.contour(volume, iso, spacing=(0.5, 0.5, 0.5))
print(mesh)

# One point per grid edge whose two samples straddle the isovalue (inside: value >= iso).
inside = volume >= iso
crossed = sum(int(np.count_nonzero(np.diff(inside, axis=a))) for a in range(3))
assert len(mesh.points) == crossed, (len(mesh.points), crossed)

report = keymesh.check(mesh)
assert report["closed_manifold"] and report["components"] == 1, report
assert report["euler_characteristic"] == 2, report  # one sphere: the two balls merged

folder = sys.argv[1] if len(sys.argv) > 1 else "."
for name in ("blob.ply", "blob.vtp"):
    path = os.path.join(folder, name)
    keymesh.write(mesh, path)
    back = keymesh.read(path)
    assert np.array_equal(back.points, mesh.points) and np.array_equal(back.cells, mesh.cells), path
    for field, values in mesh.point_data.items():
        assert np.array_equal(back.point_data[field], values), (path, field)
    print("wrote", path)
