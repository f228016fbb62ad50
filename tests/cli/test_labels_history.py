"""`keymesh labels --history` (issue 37): per-point history_key and history_t
of label surfaces (docs/HISTORY.md).

An int16 label map (boxes in label noise: triple lines, diagonal contacts,
regions touching the border) on a grid with its own spacing and origin.
Read back with VTK's own reader, and checked independently of keymesh: the
keys decoded in numpy as the doc says, in the volume padded with one sample
of background all round (p = i + (nx + 2) * (j + (ny + 2) * k) for padded
point (i, j, k), sample (i - 1, j - 1, k - 1)):
  - discrete MC (--smooth 0): history_key = 3 * p + axis names exactly the
    padded grid edges between two labels (per label: with one end of the
    label), once each; t = 0.5 and float32(origin + spacing * (c + t)) along
    the axis (c = p's sample coordinates), the grid line elsewhere, is every
    point bit for bit;
  - surface nets (--smooth 0): history_key = 16 * p + slot names exactly the
    cells (first corner p) with more than one label; every network point is
    the cell centre float32(origin + spacing * (c + 0.5)) bit for bit; per
    label, single-loop cells and face points are reproduced bit for bit and
    multi-loop points lie in their cell;
  - smoothing keeps the keys and t (same order, same triangles) and, for
    surface nets, every point in its cell;
  - the arrays are the same bytes at 1 and 2 threads, in slabs
    (--memory-limit), gathered under mpirun -np 2 and in .pvtp pieces
    (surface nets and discrete MC);
  - what cannot hold a history is refused by name (.ply/.obj/.stl/.glb,
    --coarsen, --format precomputed, --backend cuda).
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (assert_pieces_carry_history, boxes_in_noise, check, finish, history_arrays, mpirun,  # noqa: E402
                    mpirun_runs, require_vtk, run, tempdir, write_raw)

require_vtk()
import numpy as np  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

from kmtest import read_polydata  # noqa: E402

D = tempdir()
SHAPE = (10, 9, 12)  # x, y, z
VOLUME = boxes_in_noise(SHAPE, 37, [(5, np.s_[1:6, 2:7, 2:9]), (9, np.s_[3:9, 1:6, 5:12])], 0.3)
SPACING = np.array([0.5, 0.75, 1.25])
ORIGIN = np.array([3.0, -1.5, 2.0])
RAW = ["--dims", *SHAPE, "--type", "int16", "--spacing", *SPACING, "--origin", *ORIGIN]
VOL = write_raw(os.path.join(D, "labels.raw"), VOLUME)
PADDED = np.pad(VOLUME, 1)  # background 0 all round: [x, y, z]
PX, PY, PZ = PADDED.shape


def labels(name, *extra):
    out = os.path.join(D, name + ".vtp")
    run("labels", VOL, *RAW, "--history", "-o", out, "-q", *extra)
    return out


def history(path):
    """points (float32), history_key (uint64), history_t (float32), triangles, cell label (or None)."""
    poly = read_polydata(path)
    points, keys, t = history_arrays(poly, path)
    tris = ns.vtk_to_numpy(poly.GetPolys().GetConnectivityArray()).astype(np.int64).reshape(-1, 3)
    label = poly.GetCellData().GetArray("label")
    return points, keys, t, tris, None if label is None else ns.vtk_to_numpy(label)


def padded_ijk(p):
    return np.stack([p % PX, p // PX % PY, p // (PX * PY)], axis=1)


def point_labels(n, tris, label):
    """Per point, the label of the faces using it (per-label surfaces)."""
    out = np.full(n, -1, np.int64)
    out[tris.reshape(-1)] = np.repeat(label.astype(np.int64), 3)
    assert (out >= 0).all()
    return out


def differing_edges(inside=None):
    """Keys 3 * p + axis of the padded grid edges whose ends differ (or, with
    `inside` a boolean map, whose ends differ in it)."""
    v = PADDED if inside is None else inside
    ids = np.arange(PADDED.size).reshape(PADDED.shape, order="F")
    keys = []
    for axis in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[axis], hi[axis] = slice(0, -1), slice(1, None)
        cut = v[tuple(lo)] != v[tuple(hi)]
        keys.append(3 * ids[tuple(lo)][cut] + axis)
    return np.sort(np.concatenate(keys)).astype(np.uint64)


def mixed_cells(inside=None):
    """Padded ids of the first corners of cells whose 8 corners differ."""
    v = PADDED if inside is None else inside
    corners = [v[dx:PX - 1 + dx, dy:PY - 1 + dy, dz:PZ - 1 + dz] for dx in (0, 1) for dy in (0, 1) for dz in (0, 1)]
    mixed = np.zeros(corners[0].shape, bool)
    for c in corners[1:]:
        mixed |= c != corners[0]
    ids = np.arange(PADDED.size).reshape(PADDED.shape, order="F")[:-1, :-1, :-1]
    return np.sort(ids[mixed]).astype(np.int64)


def at(c, t_along=None, axis=None):
    """float32(origin + spacing * (c + t)) of sample coordinates c (n, 3)."""
    u = c.astype(np.float64)
    if axis is not None:
        u[np.arange(len(u)), axis] += t_along
    return (ORIGIN + SPACING * u).astype(np.float32)


def discrete_mc_reproduced():
    for per_label in (False, True):
        extra = ["--per-label"] if per_label else []
        points, keys, t, tris, label = history(labels(f"dmc{int(per_label)}", "--method", "discrete-mc",
                                                      "--smooth", "0", *extra))
        assert np.all(t == np.float32(0.5))
        p, axis = (keys // np.uint64(3)).astype(np.int64), (keys % np.uint64(3)).astype(np.int64)
        ijk = padded_ijk(p)
        again = at(ijk - 1, t.astype(np.float64), axis)
        assert np.array_equal(again, points), np.flatnonzero(np.any(again != points, axis=1))[:5]
        if not per_label:
            assert np.array_equal(np.sort(keys), differing_edges()), "not the edges between two labels"
            continue
        owner = point_labels(len(points), tris, label)
        for value in np.unique(owner):
            mine = np.sort(keys[owner == value])
            assert np.array_equal(mine, differing_edges(PADDED == value)), value


def surface_nets_reproduced():
    points, keys, t, _, _ = history(labels("sn_net", "--smooth", "0"))
    assert np.all(t == np.float32(0.5)) and np.all(keys % np.uint64(16) == 0)
    cells = (keys // np.uint64(16)).astype(np.int64)
    assert np.array_equal(np.sort(cells), mixed_cells()), "not the cells with more than one label"
    again = at(padded_ijk(cells) - 1 + 0.5)
    assert np.array_equal(again, points)


def surface_nets_per_label_reproduced():
    points, keys, t, tris, label = history(labels("sn_per", "--smooth", "0", "--per-label"))
    assert np.all(t == np.float32(0.5))
    owner = point_labels(len(points), tris, label)
    cells = (keys // np.uint64(16)).astype(np.int64)
    slot = (keys % np.uint64(16)).astype(np.int64)
    assert slot.max() <= 9
    ijk = padded_ijk(cells)
    centre = at(ijk - 1 + 0.5)
    counted = {"single": 0, "loops": 0, "face": 0}
    for value in np.unique(owner):
        mine = owner == value
        assert len(np.unique(keys[mine])) == mine.sum(), f"label {value}: two points share a key"
        loop_cells = cells[mine & (slot < 4)]
        assert np.array_equal(np.unique(loop_cells), mixed_cells(PADDED == value)), value
        # Cells with one loop: the centre, bit for bit; with several: in the cell.
        count = dict(zip(*np.unique(loop_cells, return_counts=True)))
        single = mine & (slot < 4) & np.array([count.get(c, 0) == 1 for c in cells])
        assert np.array_equal(points[single], centre[single]), value
        several = mine & (slot < 4) & ~single
        assert np.all(np.abs(points[several] - centre[several]) <= SPACING / 2 + 1e-5)
        counted["single"] += single.sum()
        counted["loops"] += several.sum()
        # Face points: on the face (normal d) of the cell's first corner,
        # 0.25 / 0.75 along its two spanning axes from the arc's label corner.
        for i in np.flatnonzero(mine & (slot >= 4)):
            d, arc = (slot[i] - 4) // 2, (slot[i] - 4) % 2
            s1, s2 = [a for a in range(3) if a != d]
            c00 = PADDED[tuple(ijk[i])] == value
            o1, o2 = arc, (arc if c00 else 1 - arc)
            u = ijk[i].astype(np.float64) - 1
            u[s1] += 0.75 if o1 else 0.25
            u[s2] += 0.75 if o2 else 0.25
            assert np.array_equal((ORIGIN + SPACING * u).astype(np.float32), points[i]), (value, i)
            counted["face"] += 1
    print(f"  per label: {counted}")
    assert counted["single"] > 0 and counted["loops"] > 0


def smoothing_keeps_the_history():
    for method in ("surfacenets", "discrete-mc"):
        for extra in ([], ["--per-label"]):
            name = f"{method}{len(extra)}"
            p0, k0, t0, tri0, _ = history(labels(name + "_s0", "--method", method, "--smooth", "0", *extra))
            p1, k1, t1, tri1, _ = history(labels(name + "_s16", "--method", method, *extra))
            assert np.array_equal(k0, k1) and np.array_equal(t0, t1) and np.array_equal(tri0, tri1), name
            assert not np.array_equal(p0, p1), f"{name}: smoothing moved nothing"
            if method == "surfacenets":
                # Smoothing keeps a point within half a spacing of where it
                # started: its cell (a face point: around the face point).
                cells = (k1 // np.uint64(16)).astype(np.int64)
                centre = at(padded_ijk(cells) - 1 + 0.5).astype(np.float64)
                in_cell = k1 % np.uint64(16) < 4
                assert np.all(np.abs(p1 - centre)[in_cell] <= SPACING / 2 + 1e-5), name
                assert np.all(np.abs(p1 - p0.astype(np.float64))[~in_cell] <= SPACING / 2 + 1e-5), name


def same_history_any_way():
    plane = SHAPE[0] * SHAPE[1] * 2 + (SHAPE[0] + 2) * (SHAPE[1] + 2) * 2
    for method in ("surfacenets", "discrete-mc"):
        for extra in ([], ["--per-label"]):
            name = f"any_{method}{len(extra)}"
            ref = open(labels(name, "--method", method, "--threads", "2", *extra), "rb").read()
            assert b"history_key" in ref
            assert open(labels(name + "_t1", "--method", method, "--threads", "1", *extra), "rb").read() == ref
            if (method == "surfacenets") == bool(extra):  # slabs: surface nets per label, discrete MC's network
                out = labels(name + "_slabs", "--method", method, "--memory-limit", str(3 * plane), *extra)
                assert open(out, "rb").read() == ref, f"{name}: --memory-limit of 3 planes"


def no_history_without_the_flag():
    out = os.path.join(D, "plain.vtp")
    run("labels", VOL, *RAW, "-o", out, "-q")
    pd = read_polydata(out).GetPointData()
    assert pd.GetArray("history_key") is None and pd.GetArray("history_t") is None


def refusals():
    cases = [([], "ply", "only .vtp"), ([], "obj", "only .vtp"), ([], "stl", "only .vtp"), ([], "glb", "only .vtp"),
             (["--coarsen"], "vtp", "--coarsen"),
             (["--backend", "cuda", "--smooth", "0"], "vtp", "per-point history (--history)")]
    for extra, ext, needle in cases:
        out = os.path.join(D, "refused." + ext)
        p = run("labels", VOL, *RAW, "--history", "-o", out, *extra, expect=None)
        assert p.returncode != 0 and needle in p.stderr, (extra, ext, p.returncode, p.stderr)
        assert p.stderr.count("\n") == 1, p.stderr
        assert not os.path.exists(out), out
    out = os.path.join(D, "refused_precomputed")
    p = run("labels", VOL, *RAW, "--history", "--format", "precomputed", "-o", out, expect=None)
    assert p.returncode == 2 and "--format precomputed" in p.stderr and p.stderr.count("\n") == 1, p.stderr
    assert not os.path.exists(out)


def under_mpirun():
    if not mpirun_runs("labels", VOL, *RAW, "-o", os.path.join(D, "probe.vtp"), "-q"):
        return
    for method in ("surfacenets", "discrete-mc"):
        ref_path = labels(f"mpi_ref_{method}", "--method", method)
        if method == "surfacenets":
            out = os.path.join(D, f"mpi_{method}.vtp")
            mpirun(2, "labels", VOL, *RAW, "--method", method, "--history", "-o", out, "-q")
            assert open(out, "rb").read() == open(ref_path, "rb").read(), f"{method}: gathered .vtp differs"
        # Pieces (ghost points too): every point carries the one process's
        # key, t and position (network keys are unique).
        index = os.path.join(D, f"pieces_{method}.pvtp")
        mpirun(2, "labels", VOL, *RAW, "--method", method, "--history", "-o", index, "-q")
        assert_pieces_carry_history(ref_path, index, 2)


check("discrete MC (--smooth 0): key = the padded edge, t = 0.5 give every point back", discrete_mc_reproduced)
check("surface nets (--smooth 0): key = the mixed cell, every point its centre", surface_nets_reproduced)
check("surface nets per label: loops and face points reproduced", surface_nets_per_label_reproduced)
check("smoothing keeps keys, t and triangles (surface nets: in the cell)", smoothing_keeps_the_history)
check("the same bytes at 1 and 2 threads and in slabs of 3 planes", same_history_any_way)
check("no history arrays without --history", no_history_without_the_flag)
check("--history with .ply/.obj/.stl/.glb, --coarsen, cuda, precomputed: refused by name", refusals)
check("mpirun -np 2: gathered .vtp the same bytes; .pvtp pieces carry every point's history", under_mpirun)
finish()
