"""`mpirun -np P keymesh labels ... -o OUT.pvtp` (issue 36): every rank writes
its own piece, nothing is gathered on rank 0. Each rank makes its rows plus
halo rows either side, smooths and coarsens them as one process does, and
writes its own triangles (and ghost cells) with their points' global ids.

Checked against the single-process run of the same keymesh (whose surfaces
test_labels_cli.py checks against numpy and skimage), on a volume taller than
the halos, so that no rank sees the whole: P pieces and one index are
written; VTK's reader gives the pieces, and welded by their GlobalPointIds
they hold the one process's points in its order with the same bits, and its
triangles with the same cell fields (the pieces' triangles run rank by rank);
keymesh's own .pvtp reader welds them the same way; the report's label pairs
(faces, distinct points), summed from the ranks' shares, are one process's; each rank's
guard_shortened (halo rows included) adds up to at least one process's count; the report says
"output": "pieces" with every rank's peak memory and bytes sent and no
gather stage; a rank without rows writes an empty piece; a piece that cannot
be written ends every rank with one message, and no index. Surface nets and
discrete MC, one network and --per-label, smoothed, coarsened, and with
--memory-limit on every rank. Skipped (77) without mpirun, MPI or VTK."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (boxes_in_noise, check, finish, mpirun, read_polydata, report, require_mpi,  # noqa: E402
                    require_vtk, run, tempdir, triangles_of, welded_vtk_pieces, write_raw)

require_vtk()
import numpy as np  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

D = tempdir()
SHAPE = (9, 8, 64)  # x, y, z: 66 padded rows, 22 a rank at -np 3, halos of 10 to 16 rows (2 a step + 4 or 8)
vol = boxes_in_noise(SHAPE, 36, [(5, np.s_[1:6, 2:7, 2:20]), (9, np.s_[3:8, 1:6, 12:37])], 0.35)
VOL = write_raw(os.path.join(D, "mix.raw"), vol)
RAW = ["--dims", *SHAPE, "--type", "int16"]
require_mpi("labels", VOL, *RAW, "-o", os.path.join(D, "probe.vtp"), "-q")


def cell_rows(poly, tris, keep=None):
    """Each triangle (kept) with its cell fields, as rows sorted as a multiset."""
    keep = np.ones(len(tris), bool) if keep is None else keep
    cols = [tris[keep].astype(np.float64)]
    for name in ("boundary_labels", "label"):
        a = poly.GetCellData().GetArray(name)
        if a is not None:
            cols.append(ns.vtk_to_numpy(a).reshape(len(tris), -1)[keep].astype(np.float64))
    rows = np.concatenate(cols, axis=1)
    return rows[np.lexsort(rows.T[::-1])]


def welded_by_vtk(index, P, n_points):
    """The pieces welded by GlobalPointIds (kmtest.welded_vtk_pieces):
    points (float32, by id) and the rows of the pieces' own triangles."""
    pts, _, rows = welded_vtk_pieces(index, P, n_points, cell_rows)
    merged = np.concatenate(rows)
    return pts, merged[np.lexsort(merged.T[::-1])]


guard_seen = []  # one process's guard_shortened of each run checked


def pieces_equal_one_process(args, ranks=(2, 3), extra=()):
    def fn():
        ref_path = os.path.join(D, "ref.vtp")
        run("labels", VOL, *RAW, *args, "-o", ref_path, "-q", "--report", ref_path + ".json")
        ref_pairs = report(ref_path + ".json")["pairs"]
        ref_guard = report(ref_path + ".json")["guard_shortened"]
        ref = read_polydata(ref_path)
        ref_pts = ns.vtk_to_numpy(ref.GetPoints().GetData()).astype(np.float32)
        ref_rows = cell_rows(ref, triangles_of(ref))
        for P in ranks:
            sub = os.path.join(D, f"p{P}_{abs(hash(tuple(args))) % 10**8}")
            os.makedirs(sub, exist_ok=True)
            index, rep = os.path.join(sub, "x.pvtp"), os.path.join(sub, "x.json")
            mpirun(P, "labels", VOL, *RAW, *args, *extra, "-o", index, "-q", "--report", rep)
            assert sorted(os.listdir(sub)) == sorted(["x.pvtp", "x.json"] + [f"x_{q}.vtp" for q in range(P)])
            pts, rows = welded_by_vtk(index, P, len(ref_pts))
            assert np.array_equal(pts.view(np.uint32), ref_pts.view(np.uint32)), "welded points differ"
            assert np.array_equal(rows, ref_rows), "welded triangles or their cell fields differ"
            r = report(rep)
            d = r["distributed"]
            assert d["output"] == "pieces" and d["ranks"] == P and len(d["per_rank"]) == P, d
            assert r["points"] == len(ref_pts) and r["cells"] == len(ref_rows), (r["points"], r["cells"])
            assert r["pairs"] == ref_pairs and len(ref_pairs) > 3, (r["pairs"], ref_pairs)
            assert "gather" not in r["seconds"] and "merge" not in r["seconds"], r["seconds"]
            for q in d["per_rank"]:
                assert q["peak_rss_mib"] > 0 and q["bytes_sent"] >= 0 and q["halo_rows"] > 0, q
            assert sum(q["triangles"] for q in d["per_rank"]) == len(ref_rows)
            # Each rank's fold guard count, its halo rows included: every point's moves are made by
            # its owner as by one process, so the ranks' sum is at least one process's count; no total.
            shortened = [q["guard_shortened"] for q in d["per_rank"]]
            assert min(shortened) >= 0 and sum(shortened) >= ref_guard, (shortened, ref_guard)
            assert "guard_shortened" not in r, r.keys()
            guard_seen.append(ref_guard)
            assert sum(q["points_owned"] for q in d["per_rank"]) <= len(ref_pts)
            assert max(q["rows"] + q["halo_rows"] for q in d["per_rank"]) < SHAPE[2] + 2, "a rank held every row"
            # keymesh's own reader welds the pieces by their ids too.
            conv = os.path.join(sub, "conv.vtp")
            run("convert", index, "-o", conv, "-q")
            back = read_polydata(conv)
            assert np.array_equal(ns.vtk_to_numpy(back.GetPoints().GetData()).view(np.uint32), ref_pts.view(np.uint32))
            assert np.array_equal(cell_rows(back, triangles_of(back)), ref_rows), "keymesh's reader: triangles differ"
    return fn


for method in ("surfacenets", "discrete-mc"):
    for per_label in ([], ["--per-label"]):
        args = ["--method", method, *per_label, "--smooth", "3"]
        check(f"{' '.join(args)}: -np 2, 3 pieces welded by global ids equal one process",
              pieces_equal_one_process(args))
    args = ["--method", method, "--smooth", "2", "--coarsen"]
    check(f"{' '.join(args)}: -np 3 pieces equal one process", pieces_equal_one_process(args, (3,)))
    args = ["--method", method, "--per-label", "--smooth", "2", "--coarsen"]
    check(f"{' '.join(args)}: -np 2 pieces equal one process", pieces_equal_one_process(args, (2,)))


def fold_guard_acted():
    assert guard_seen and max(guard_seen) > 0, guard_seen


check("the fold guard acted in those runs, so the ranks' guard_shortened sums above were checked against a count > 0",
      fold_guard_acted)

plane = SHAPE[0] * SHAPE[1] * 2 + (SHAPE[0] + 2) * (SHAPE[1] + 2) * 2
check("--memory-limit on every rank (one row per slab), surface nets per label: pieces equal one process",
      pieces_equal_one_process(["--per-label", "--smooth", "3"], (3,), ["--memory-limit", 3 * plane]))


def default_smoothing_on_a_tall_volume():
    """Default smoothing (16 steps: halos of 36 rows, 68 for discrete-mc's
    Taubin steps; two rows a step) on 258 padded rows over 3 ranks: no rank
    sees them all."""
    tall = os.path.join(D, "tall.raw")
    big = np.concatenate([vol, vol[:, :, ::-1], vol, vol[:, :, ::-1]], axis=2)
    assert big.shape[2] == 256
    with open(tall, "wb") as f:
        f.write(big.tobytes(order="F"))
    raw = ["--dims", SHAPE[0], SHAPE[1], big.shape[2], "--type", "int16"]
    for method in ("surfacenets", "discrete-mc"):
        ref, index = os.path.join(D, f"tall_{method}.vtp"), os.path.join(D, f"tall_{method}.pvtp")
        run("labels", tall, *raw, "--method", method, "-o", ref, "-q")
        mpirun(3, "labels", tall, *raw, "--method", method, "-o", index, "-q", "--report", index + ".json")
        d = report(index + ".json")["distributed"]
        assert max(q["rows"] + q["halo_rows"] for q in d["per_rank"]) < big.shape[2] + 2, d["per_rank"]
        a = read_polydata(ref)
        pts, rows = welded_by_vtk(index, 3, a.GetNumberOfPoints())
        assert np.array_equal(pts.view(np.uint32), ns.vtk_to_numpy(a.GetPoints().GetData()).view(np.uint32)), method
        assert np.array_equal(rows, cell_rows(a, triangles_of(a))), method


check("default smoothing (16 steps) on a taller volume, both methods, -np 3: pieces equal one process",
      default_smoothing_on_a_tall_volume)


def thin_volume_rank_without_rows():
    thin = os.path.join(D, "thin.raw")
    open(thin, "wb").write(vol[:, :, 5:6].tobytes(order="F"))
    raw = ["--dims", SHAPE[0], SHAPE[1], 1, "--type", "int16"]
    ref = os.path.join(D, "thin.vtp")
    run("labels", thin, *raw, "-o", ref, "-q")
    sub = os.path.join(D, "thin")
    os.makedirs(sub)
    mpirun(4, "labels", thin, *raw, "-o", os.path.join(sub, "t.pvtp"), "-q")
    assert len([f for f in os.listdir(sub) if f.endswith(".vtp")]) == 4
    conv = os.path.join(sub, "t.vtp")
    run("convert", os.path.join(sub, "t.pvtp"), "-o", conv, "-q")
    a, b = read_polydata(ref), read_polydata(conv)
    assert np.array_equal(ns.vtk_to_numpy(a.GetPoints().GetData()), ns.vtk_to_numpy(b.GetPoints().GetData()))
    assert np.array_equal(cell_rows(a, triangles_of(a)), cell_rows(b, triangles_of(b)))


check("a one-plane volume on 4 ranks (a rank without rows): its piece is empty, the whole equals one process",
      thin_volume_rank_without_rows)


def gathered_stays_byte_identical():
    for args in (["--smooth", "3", "--coarsen"], ["--method", "discrete-mc", "--per-label", "--smooth", "2"]):
        ref, out = os.path.join(D, "g1.vtp"), os.path.join(D, "g3.vtp")
        run("labels", VOL, *RAW, *args, "-o", ref, "-q")
        mpirun(3, "labels", VOL, *RAW, *args, "-o", out, "-q")
        assert open(out, "rb").read() == open(ref, "rb").read(), args


check("a non-.pvtp output is still gathered, byte-identical to one process", gathered_stays_byte_identical)


def unwritable_piece_fails_once():
    p = mpirun(3, "labels", VOL, *RAW, "-o", os.path.join(D, "nowhere", "x.pvtp"), expect=1)
    said = [line for line in p.stderr.splitlines() if line.startswith("keymesh")]
    assert len(said) == 1 and "nowhere" in said[0], p.stderr
    assert not os.path.exists(os.path.join(D, "nowhere"))


check("a piece that cannot be written: one message, exit 1, no index, no hang", unwritable_piece_fails_once)

finish()
