"""keymesh.marching_cubes(..., history=True): two more arrays, history_key
(uint64) and history_t (float32), in keymesh.contour's key frame
(docs/HISTORY.md). Decoded in numpy: every vertex is given back from its
edge and t, the keys name exactly the cut edges of the (step_size) lattice,
and they are keymesh.contour's keys for the same edges of the same array."""
import numpy as np
import pytest

import keymesh
from conftest import smooth_random_field


def volume(shape=(19, 17, 21), seed=5):
    return smooth_random_field(shape, seed=seed, passes=3).astype(np.float32)


def decode(key, shape):
    """lower end (array index), array axis of each edge key; cube centres apart."""
    n = int(np.prod(shape))
    centre = key >= 3 * n
    edge = np.where(centre, (key - 3 * n) * 3, key)
    point, axis = edge // 3, edge % 3
    lo = np.stack(np.unravel_index(point.astype(np.int64), shape, order="F"), axis=1)
    return lo, axis.astype(np.int64), centre


def cut_edges(v, level, step):
    """contour-frame keys of the lattice edges (step samples long) the level cuts (value > level inside)."""
    keys = []
    ids = np.arange(v.size).reshape(v.shape, order="F")
    sub = v[::step, ::step, ::step]
    sub_ids = ids[::step, ::step, ::step]
    # the lattice only covers whole cubes
    n = [(s - 1) // step + 1 for s in v.shape]
    sub, sub_ids = sub[:n[0], :n[1], :n[2]], sub_ids[:n[0], :n[1], :n[2]]
    inside = sub > level
    for axis in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[axis], hi[axis] = slice(0, -1), slice(1, None)
        cut = inside[tuple(lo)] != inside[tuple(hi)]
        keys.append(3 * sub_ids[tuple(lo)][cut] + axis)
    return np.sort(np.concatenate(keys)).astype(np.uint64)


@pytest.mark.parametrize("method,step,spacing", [("lorensen", 1, (1, 1, 1)), ("lorensen", 2, (0.5, 1.5, 2.0)),
                                                  ("lewiner", 1, (1, 1, 1)), ("lewiner", 3, (0.7, 1.0, 1.3))])
def test_vertices_from_key_and_t(method, step, spacing):
    if method == "lewiner":
        pytest.importorskip("skimage.measure")
    v = volume()
    level = 0.0
    verts, faces, normals, values, key, t = keymesh.marching_cubes(v, level, spacing=spacing, step_size=step,
                                                                   method=method, history=True)
    plain = keymesh.marching_cubes(v, level, spacing=spacing, step_size=step, method=method)
    assert len(plain) == 4
    for a, b in zip(plain, (verts, faces, normals, values)):
        assert np.array_equal(a, b)
    assert key.dtype == np.uint64 and t.dtype == np.float32 and len(key) == len(verts) == len(t)
    assert len(np.unique(key)) == len(key)
    lo, axis, centre = decode(key, v.shape)
    edges = ~centre
    assert np.array_equal(np.sort(key[edges]), cut_edges(v, level, step))
    # the documented formula: verts[:, A] = float32(lo[A] + step * t) * spacing[A]
    rows = np.flatnonzero(edges)
    u = lo[rows].astype(np.float64)
    r = np.arange(len(rows))
    u[r, axis[rows]] += step * t[rows].astype(np.float64)
    again = u.astype(np.float32).astype(np.float64) * np.r_[spacing]
    written = verts[rows].astype(np.float64)
    off = np.ones(u.shape, bool)
    off[r, axis[rows]] = False
    assert np.array_equal(again[off], written[off])
    along, along_again = written[r, axis[rows]], again[r, axis[rows]]
    # Bit for bit an edge or more from zero (there a float t gives it back);
    # nearer, within step * 2^-25 plus one float32 step (docs/HISTORY.md).
    unscaled = u[r, axis[rows]]
    far = unscaled >= step
    assert np.array_equal(along_again[far], along[far])
    bound = (step * 2.0 ** -25 + np.spacing(np.abs(unscaled).astype(np.float32))) * np.r_[spacing][axis[rows]]
    assert np.all(np.abs(along_again - along) <= bound * (1 + 1e-9))
    assert far.mean() > 0.8
    assert np.all((t[edges] >= 0) & (t[edges] <= 1))
    # cube centres (lewiner only): inside their cube, t = 0.5
    if method == "lorensen":
        assert not centre.any()
    else:
        assert np.all(t[centre] == np.float32(0.5))
        inside = (verts[centre] >= lo[centre] * np.r_[spacing] - 1e-6) & \
                 (verts[centre] <= (lo[centre] + step) * np.r_[spacing] + 1e-6)
        assert inside.all()


def test_keys_are_keymesh_contours():
    v = volume()
    _, _, _, _, key, _ = keymesh.marching_cubes(v, 0.0, method="lorensen", history=True)
    m = keymesh.contour(v, 0.0, normals="none", history=True)  # no sample equals the level here
    assert np.array_equal(np.sort(key), np.sort(m.point_data["history_key"]))


def test_degenerate_faces_removed_with_their_history():
    v = np.zeros((6, 7, 8), np.float32)
    v[2:4, 2:5, 3:6] = 1.0  # samples equal to the level at 0: points on samples,
    v[4:5, 2:3, 3:4] = 1.0  # and concave corners, where two edges' points coincide
    v[2:3, 5:6, 5:6] = 1.0
    full = keymesh.marching_cubes(v, 0.0, method="lorensen", history=True)
    verts, faces, normals, values, key, t = keymesh.marching_cubes(v, 0.0, method="lorensen", history=True,
                                                                   allow_degenerate=False)
    assert len(verts) < len(full[0])
    by_key = {int(k): (tuple(p), float(tt)) for k, p, tt in zip(full[4], full[0], full[5])}
    for k, p, tt in zip(key, verts, t):
        assert by_key[int(k)] == (tuple(p), float(tt))


def test_old_lorensen_refuses_history():
    with pytest.raises(ValueError, match="history"):
        keymesh.marching_cubes(volume(), 0.0, method="_lorensen", history=True)
