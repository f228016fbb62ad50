"""Topology checks of triangle lists (numpy int arrays of shape (m, 3)) shared by
the command's tests (tests/cli) and the module's (tests/python)."""
import numpy as np


def assert_closed_manifold(tris, what):
    """Every edge in exactly two triangles, used in opposite directions (consistent
    orientation), and every vertex's link one cycle."""
    directed = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    d = {tuple(x) for x in directed}
    assert len(d) == len(directed), f"{what}: a directed edge used twice (orientation or non-manifold edge)"
    for a, b in d:
        assert (b, a) in d, f"{what}: edge {a}-{b} has no opposite (boundary)"
    links = {}
    for a, b, c in tris:
        for v, e in ((a, (b, c)), (b, (c, a)), (c, (a, b))):
            links.setdefault(v, []).append(e)
    for v, es in links.items():
        nxt = dict(es)
        assert len(nxt) == len(es), f"{what}: vertex {v} fan is not a disk"
        start, cur, steps = es[0][0], nxt[es[0][0]], 1
        while cur != start:
            cur, steps = nxt[cur], steps + 1
        assert steps == len(es), f"{what}: vertex {v} has {len(es)} triangles in more than one fan"
