"""KEY-REDUCE on your own keys: one midpoint per edge of a triangle mesh.

    every triangle emits its 3 edge midpoints,      keymesh.key_reduce groups them by key:
    each keyed by its edge (smaller id, larger id)  one midpoint per edge, the copies averaged;
    ->  a soup of 3 x triangles midpoints      ->   index_map: the edge of every triangle side

No coordinate is compared: two triangles that share an edge give it the same key.
Checks: as many midpoints as the mesh has edges (keymesh.check counts them), each made
from exactly two copies (a closed surface), each the exact midpoint of its edge.
Run: PYTHONPATH=build/python /usr/bin/python3 examples/key_reduce.py
"""
import numpy as np

import keymesh

i, j, k = np.indices((40, 40, 40), dtype=np.float32)
sphere = keymesh.contour(np.sqrt((i - 19.5) ** 2 + (j - 20) ** 2 + (k - 21) ** 2), 15.5, normals=None)
points, triangles = sphere.points, sphere.cells.astype(np.uint64)

# Map: the sides (a, b), (b, c), (c, a) of every triangle, keyed by their smaller and larger point id.
a, b = triangles, np.roll(triangles, -1, axis=1)
lo, hi = np.minimum(a, b).reshape(-1), np.maximum(a, b).reshape(-1)
keys = lo * np.uint64(len(points)) + hi
midpoints = (points[lo.astype(np.int64)] + points[hi.astype(np.int64)]) / 2  # one copy per side

# KEY-REDUCE: group the copies by key, average each group.
edge_keys, edge_midpoints, index_map, counts = keymesh.key_reduce(keys, midpoints, op="mean")
print(f"{len(keys)} sides -> {len(edge_keys)} edges")

assert len(edge_keys) == keymesh.check(sphere)["edges"]
assert np.all(counts == 2)  # closed: every edge between two triangles
assert np.all(np.diff(edge_keys.astype(np.int64)) > 0)  # groups in increasing key order
assert np.array_equal(edge_keys[index_map], keys)  # index_map: the edge of every side
lo_e, hi_e = (edge_keys // np.uint64(len(points))).astype(np.int64), (edge_keys % np.uint64(len(points))).astype(np.int64)
assert np.array_equal(edge_midpoints, (points[lo_e] + points[hi_e]) / 2)  # two equal copies: exact mean
