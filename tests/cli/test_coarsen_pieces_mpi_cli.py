"""`mpirun -np P keymesh contour ... --coarsen -o OUT.pvtp` (issue 36): every
rank writes its own piece of the coarsened surface, nothing is gathered on
rank 0. Each rank contours its voxel layers plus halo layers either side,
coarsens them as one process does (the non-manifold split's rounds agreed by
all ranks), checks that no decision of the split reaching a point it writes
touched its halo's cut, grows the halo otherwise, and writes its triangles
(and ghost cells) with their points' global ids.

Checked against the single-process run of the same keymesh (whose coarsening
test_coarsen_distributed_cli.py and the C++ tests check): P pieces and one
index are written; VTK's reader gives the pieces, and welded by their
GlobalPointIds they hold the one process's points in its order with the same
bits, its triangles (as a multiset: pieces run rank by rank) and, with
averaged or gradient normals, its normals bit for bit; keymesh's own .pvtp
reader welds them the same way; the report's counts (triangles before and
after, non-manifold edges and vertices, boundary edges), summed from the
ranks' shares, are one process's; the report says "output": "pieces" with
every rank's halo and no gather stage. Smoothed noise (many pinched sheets
and splits), two isovalues, -np 2 and 3; a plate one voxel thick whose two
sides' crossings lie nearest the plate's grid points, spanning every slab,
makes the check grow the halo (its chains of points that are not one closed
fan run the plate's length); brainsmall.den when installed. Skipped (77) without mpirun, MPI
or VTK."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (box_filtered_noise, check, finish, mpirun, one_voxel_plate, read_polydata, report,  # noqa: E402
                    require_mpi, require_vtk, run, tempdir, triangles_of, welded_vtk_pieces)

require_vtk()
import numpy as np  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

D = tempdir()
NX, NY, NZ = 33, 29, 40  # 39 voxel layers: 13 a rank at -np 3, halos of 8 first
NOISE = os.path.join(D, "noise.raw")
box_filtered_noise((NZ, NY, NX), 23).tofile(NOISE)
SRC = [NOISE, "--dims", NX, NY, NZ]
BRAIN = "/usr/share/doc/libvolpack1-dev/examples/brainsmall.den"
COUNTS = ("triangles_before", "triangles_after", "nonmanifold_edges", "nonmanifold_vertices", "boundary_edges")
require_mpi("contour", *SRC, "--iso", 0.5, "-o", os.path.join(D, "probe.vtp"), "-q")


def sorted_rows(tris):
    return tris[np.lexsort(tris.T[::-1])] if len(tris) else tris


def normals(poly):
    a = poly.GetPointData().GetArray("Normals")
    return None if a is None else ns.vtk_to_numpy(a).astype(np.float32).reshape(-1, 3)


def welded_by_vtk(index, P, n_points):
    """The pieces welded by GlobalPointIds (kmtest.welded_vtk_pieces):
    points and normals (float32, by id; every copy of a point must agree)
    and the pieces' own triangles in global ids, sorted."""
    pts, nrm, rows = welded_vtk_pieces(index, P, n_points, lambda piece, tris, owned: tris[owned], "Normals")
    if nrm is None:
        nrm = np.full((n_points, 3), np.nan, np.float32)
    return pts, nrm, sorted_rows(np.concatenate(rows))


def pieces_equal_one_process(src, args, ranks=(2, 3), min_attempts=1):
    def fn():
        tag = f"{abs(hash((tuple(map(str, src)), tuple(map(str, args))))) % 10**8}"
        ref_path = os.path.join(D, f"ref_{tag}.vtp")
        run("contour", *src, *args, "--coarsen", "-o", ref_path, "-q", "--report", ref_path + ".json")
        ref_report = report(ref_path + ".json")
        ref = read_polydata(ref_path)
        ref_pts = ns.vtk_to_numpy(ref.GetPoints().GetData()).astype(np.float32)
        ref_nrm = normals(ref)
        ref_rows = sorted_rows(triangles_of(ref))
        assert len(ref_rows) > 100 and ref_report["triangles_before"] > len(ref_rows), ref_report
        for P in ranks:
            sub = os.path.join(D, f"p{P}_{tag}")
            os.makedirs(sub, exist_ok=True)
            index, rep = os.path.join(sub, "x.pvtp"), os.path.join(sub, "x.json")
            mpirun(P, "contour", *src, *args, "--coarsen", "-o", index, "-q", "--report", rep)
            assert sorted(os.listdir(sub)) == sorted(["x.pvtp", "x.json"] + [f"x_{q}.vtp" for q in range(P)])
            pts, nrm, rows = welded_by_vtk(index, P, len(ref_pts))
            assert np.array_equal(pts.view(np.uint32), ref_pts.view(np.uint32)), "welded points differ"
            assert np.array_equal(rows, ref_rows), "welded triangles differ"
            if ref_nrm is not None:
                assert np.array_equal(nrm.view(np.uint32), ref_nrm.view(np.uint32)), "welded normals differ"
            r = report(rep)
            d = r["distributed"]
            assert d["output"] == "pieces" and d["ranks"] == P and len(d["per_rank"]) == P, d
            assert r["points"] == len(ref_pts) and r["cells"] == len(ref_rows), (r["points"], r["cells"])
            for key in COUNTS:
                assert r[key] == ref_report[key], (key, r[key], ref_report[key])
            assert "gather" not in r["seconds"], r["seconds"]
            assert d["attempts"] >= min_attempts, d
            for q in d["per_rank"]:
                assert q["peak_rss_mib"] > 0 and q["halo_layers"] >= 8 and q["attempts"] == d["attempts"], q
            assert sum(q["triangles"] for q in d["per_rank"]) == len(ref_rows)
            assert sum(q["points_owned"] for q in d["per_rank"]) <= len(ref_pts)
            # keymesh's own reader welds the pieces by their ids too.
            conv = os.path.join(sub, "conv.vtp")
            run("convert", index, "-o", conv, "-q")
            back = read_polydata(conv)
            assert np.array_equal(ns.vtk_to_numpy(back.GetPoints().GetData()).view(np.uint32), ref_pts.view(np.uint32))
            assert np.array_equal(sorted_rows(triangles_of(back)), ref_rows), "keymesh's reader: triangles differ"
        return d
    return fn


for args in (["--iso", 0.5], ["--iso", 0.52, "--normals", "average"],
             ["--iso", 0.5, "--iso", 0.47, "--normals", "gradient"]):
    check(f"smoothed noise {' '.join(map(str, args))}: -np 2, 3 pieces welded by global ids equal one process",
          pieces_equal_one_process(SRC, args))


def plate_grows_the_halo():
    """A plate one voxel thick (x = 16), spanning every slab, with values
    that make both sides' crossings nearest the plate's own grid points:
    the two sheets coarsen onto one, the split's chains run the plate's
    length, and no halo short of it holds them."""
    path = one_voxel_plate(os.path.join(D, "plate.raw"), NX, NY, NZ)
    d = pieces_equal_one_process([path, "--dims", NX, NY, NZ], ["--iso", 0.55], (3,), min_attempts=2)()
    print(f"plate: halo grown to {d['halo_layers']} layers in {d['attempts']} attempts")


check("a one-voxel plate spanning the slabs: the halo grows, the pieces still equal one process", plate_grows_the_halo)


def real_volume():
    if not os.path.exists(BRAIN):
        print(f"(no {BRAIN}: install libvolpack1-dev)")
        return
    nrrd = os.path.join(D, "brain.nrrd")  # .den is read whole only
    run("convert", BRAIN, "-o", nrrd, "-q")
    d = pieces_equal_one_process([nrrd], ["--iso", 37.3, "--normals", "average"], (3,))()
    print(f"brainsmall: halo {d['halo_layers']} layers in {d['attempts']} attempts")


check("brainsmall.den iso 37.3, averaged normals, -np 3: pieces equal one process", real_volume)


def gathered_stays_byte_identical():
    ref, out = os.path.join(D, "g1.ply"), os.path.join(D, "g3.ply")
    run("contour", *SRC, "--iso", 0.52, "--normals", "average", "--coarsen", "-o", ref, "-q")
    mpirun(3, "contour", *SRC, "--iso", 0.52, "--normals", "average", "--coarsen", "-o", out, "-q")
    assert open(out, "rb").read() == open(ref, "rb").read()


check("a non-.pvtp output is still gathered, byte-identical to one process", gathered_stays_byte_identical)


def unwritable_piece_fails_once():
    p = mpirun(3, "contour", *SRC, "--iso", 0.5, "--coarsen", "-o", os.path.join(D, "nowhere", "x.pvtp"), expect=1)
    said = [line for line in p.stderr.splitlines() if line.startswith("keymesh")]
    assert len(said) == 1 and "nowhere" in said[0], p.stderr
    assert not os.path.exists(os.path.join(D, "nowhere"))


check("a piece that cannot be written: one message, exit 1, no index, no hang", unwritable_piece_fails_once)

finish()
