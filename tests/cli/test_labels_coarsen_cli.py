"""`keymesh labels --coarsen` (issue 18): points merged by a coarser key
(surface nets: the 2x2x2 block of cells; discrete MC: the nearest grid
point), faces that collapse dropped, label pairs kept. Checked with numpy,
independently of keymesh's own code:
- what labels.hpp guarantees: every label's faces, oriented out of it, form
  a closed 2-cycle (each directed edge as often as its reverse), for both
  methods, one network and --per-label, with smoothing or without;
- every face's boundary_labels pair is the pair of two 6-neighbour voxels
  near it (within the blocks its points come from: Chebyshev distance 3 of
  its centroid, in voxels), on a map of boxes whose pairs are local;
- no collapsed face (three distinct points), fewer points than before;
- the same bytes at 1 and 2 threads, and with --memory-limit."""
import collections
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, report, require_vtk, run, tempdir  # noqa: E402

require_vtk()
import numpy as np  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

from kmtest import points_of, read_polydata, triangles_of  # noqa: E402

D = tempdir()


def write_raw(name, vol):
    path = os.path.join(D, name)
    with open(path, "wb") as f:
        f.write(vol.astype(np.int16).tobytes(order="F"))  # x fastest
    return path, ["--dims", *vol.shape, "--type", "int16"]


rng = np.random.default_rng(7)
NOISE = rng.integers(0, 4, size=(10, 9, 11))
BOXES = np.zeros((16, 14, 12), np.int16)
for lab, (x, y, z, a, b, c) in enumerate([(1, 1, 1, 6, 5, 5), (7, 1, 1, 5, 6, 4), (2, 6, 3, 7, 6, 6),
                                          (9, 7, 5, 6, 6, 6), (4, 2, 6, 4, 4, 5)], start=1):
    BOXES[x:x + a, y:y + b, z:z + c] = lab * 10
VOLUMES = {"noise": (NOISE, *write_raw("noise.raw", NOISE)), "boxes": (BOXES, *write_raw("boxes.raw", BOXES))}


def mesh(path):
    poly = read_polydata(path)
    cd = poly.GetCellData()
    fields = {cd.GetArrayName(i): ns.vtk_to_numpy(cd.GetArray(i)) for i in range(cd.GetNumberOfArrays())}
    return points_of(poly), triangles_of(poly), fields


def label_cycles_closed(tris, fields):
    pairs = fields["boundary_labels"].astype(int)
    if "label" in fields:
        lab = fields["label"].astype(int)
        groups = {L: tris[lab == L] for L in np.unique(lab)}
    else:  # network: a face's normal points from pairs[:, 0] to pairs[:, 1]
        groups = {L: np.concatenate([tris[pairs[:, 0] == L], tris[pairs[:, 1] == L][:, ::-1]])
                  for L in np.unique(pairs)}
    for L, t in groups.items():
        d = collections.Counter()
        for a, b, c in t:
            d[a, b] += 1
            d[b, c] += 1
            d[c, a] += 1
        open_edges = [e for e in d if d[e] != d[e[::-1]]]
        assert not open_edges, f"label {L}: {len(open_edges)} directed edges without their reverse"


def voxel_pairs(vol, background=0):
    """(a, b), a < b, of every grid edge with different labels, at its ends' voxels."""
    out = []
    for axis in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[axis], hi[axis] = slice(0, -1), slice(1, None)
        a, b = vol[tuple(lo)], vol[tuple(hi)]
        idx = np.argwhere(a != b)
        for i, j, k in idx:
            p, q = int(a[i, j, k]), int(b[i, j, k])
            out.append((min(p, q), max(p, q), i, j, k, axis))
    return out


def pairs_near_voxels(vol, P, tris, fields):
    # The padding counts as background: add it to the volume.
    padded = np.pad(vol, 1)
    by_pair = collections.defaultdict(list)
    for a, b, i, j, k, axis in voxel_pairs(padded):
        end = np.array([i, j, k], float)
        end[axis] += 0.5
        by_pair[a, b].append(end - 1.0)  # edge midpoint, unpadded voxel coordinates
    by_pair = {key: np.array(v) for key, v in by_pair.items()}
    pairs = fields["boundary_labels"].astype(int)
    centroids = P[tris].mean(axis=1)
    for f, (c, (a, b)) in enumerate(zip(centroids, pairs)):
        mids = by_pair.get((a, b))
        assert mids is not None, f"face {f}: pair ({a}, {b}) is no pair of neighbouring voxels"
        assert np.abs(mids - c).max(axis=1).min() <= 3.0, f"face {f}: no ({a}, {b}) voxel edge near {c}"


def coarsened(name, args):
    def fn():
        vol, path, raw = VOLUMES[name]
        fine, out, rep = (os.path.join(D, f) for f in ("fine.vtp", "c.vtp", "c.json"))
        run("labels", path, *raw, "-o", fine, *args, "-q")
        run("labels", path, *raw, "-o", out, *args, "--coarsen", "-q", "--report", rep, "--threads", "2")
        P, T, F = mesh(out)
        P0, T0, _ = mesh(fine)
        r = report(rep)
        assert r["coarsen"] and r["triangles_before"] == len(T0) and r["triangles_after"] == len(T), r
        assert len(T) > 0 and len(P) < len(P0), (len(P), len(P0))
        assert (T[:, 0] != T[:, 1]).all() and (T[:, 1] != T[:, 2]).all() and (T[:, 0] != T[:, 2]).all()
        # every point is used by a face: points whose faces all collapsed are dropped
        assert len(np.unique(T)) == len(P), (len(np.unique(T)), len(P))
        label_cycles_closed(T, F)
        pairs_near_voxels(vol, P, T, F)
        one = os.path.join(D, "c1.vtp")
        run("labels", path, *raw, "-o", one, *args, "--coarsen", "-q", "--threads", "1")
        streamed = os.path.join(D, "cs.vtp")
        plane = vol.shape[0] * vol.shape[1] * 2 + (vol.shape[0] + 2) * (vol.shape[1] + 2) * 2
        run("labels", path, *raw, "-o", streamed, *args, "--coarsen", "-q", "--memory-limit", 4 * plane)
        with open(out, "rb") as a, open(one, "rb") as b, open(streamed, "rb") as c:
            x = a.read()
            assert x == b.read(), "1 and 2 threads differ"
            assert x == c.read(), "--memory-limit differs"
    return fn


for name in ("noise", "boxes"):
    for method in ("surfacenets", "discrete-mc"):
        for per_label in ([], ["--per-label"]):
            for smooth in ("0", "8"):
                args = ["--method", method, *per_label, "--smooth", smooth]
                check(f"{name} {' '.join(args)} --coarsen: closed label cycles, pairs at their voxels, same bytes",
                      coarsened(name, args))

finish()
