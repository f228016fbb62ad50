"""`mpirun -np P keymesh contour --memory-limit SIZE`: each rank streams its
own planes (issue 36).

A rank reads its slab of planes in sub-slabs that fit the limit and merges
them by edge key, which gives the piece one read of the whole slab gives; the
rest of the distributed contour is unchanged. Checked: with -np 2 and 3 the
gathered file is byte-identical to one process (two isovalues; gradient
normals and curvature with their ghost planes; averaged normals; coarsened
with averaged normals), the .pvtp pieces are byte-identical to the pieces
written without a limit, and so are the coarsened pieces (--coarsen into
.pvtp: each rank streams its layers and halo layers, merged by key into the
fine mesh one read gives, at -np 2 and 3 and two limits; a plate one voxel
thick makes the halo grow, its planes read again through the same streamed
path). --balance, which holds a rank's planes whole, is refused by name,
said once."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, mpirun, one_voxel_plate, report, require_mpi, run, tempdir  # noqa: E402

D = tempdir()
N = 40
SPHERE = os.path.join(D, "sphere.nrrd")
run("generate", "sphere", "-n", N, "-o", SPHERE, "-q")
PLANE = N * N * 4
require_mpi("contour", SPHERE, "--iso", 12.5, "-o", os.path.join(D, "probe.ply"), "-q")

CASES = [
    ["--iso", 10.5, "--iso", 19.2],
    ["--iso", 10.5, "--normals", "gradient", "--curvature"],
    ["--iso", 12.5, "--normals", "average"],
    ["--iso", 12.5, "--coarsen", "--normals", "average"],
]


def read(path):
    with open(path, "rb") as f:
        return f.read()


def gathered_equal():
    for i, args in enumerate(CASES):
        one = os.path.join(D, f"one{i}.vtp")
        run("contour", SPHERE, "-o", one, "-q", *args)
        for P, planes in ((2, 4), (3, 5)):
            out = os.path.join(D, f"mpi{i}_{P}.vtp")
            rep = out + ".json"
            mpirun(P, "contour", SPHERE, "-o", out, "-q", "--memory-limit", planes * PLANE, "--report", rep, *args)
            assert read(out) == read(one), f"{args} -np {P} --memory-limit {planes} planes: differs from one process"
            ranks = report(rep)["distributed"]["per_rank"]
            assert len(ranks) == P and all(r["slabs"] > 1 for r in ranks), ranks  # each rank streamed


def pieces_equal():
    args = ["--iso", 12.5, "--normals", "average"]
    whole, limited = os.path.join(D, "whole.pvtp"), os.path.join(D, "limited.pvtp")
    mpirun(2, "contour", SPHERE, "-o", whole, "-q", *args)
    mpirun(2, "contour", SPHERE, "-o", limited, "-q", "--memory-limit", 3 * PLANE, *args)
    for name in ("_0.vtp", "_1.vtp"):
        assert read(limited[:-5] + name) == read(whole[:-5] + name), f"piece {name} differs"


def same_files(a, b, names):
    for name in names:
        assert read(os.path.join(a, name)) == read(os.path.join(b, name)), f"{name} differs"


def coarse_pieces(src, args, P, limits, tag):
    """Runs --coarsen into .pvtp without a limit and with each of `limits`
    (bytes); asserts every piece and the index are byte-identical and every
    rank streamed; returns the limited runs' distributed reports."""
    names = ["x.pvtp"] + [f"x_{q}.vtp" for q in range(P)]
    whole = os.path.join(D, f"{tag}_whole_{P}")
    os.makedirs(whole, exist_ok=True)
    mpirun(P, "contour", *src, "-o", os.path.join(whole, "x.pvtp"), "-q", "--coarsen", *args)
    reports = []
    for limit in limits:
        sub = os.path.join(D, f"{tag}_{P}_{limit}")
        os.makedirs(sub, exist_ok=True)
        rep = os.path.join(sub, "r.json")
        mpirun(P, "contour", *src, "-o", os.path.join(sub, "x.pvtp"), "-q", "--coarsen", "--memory-limit", limit,
               "--report", rep, *args)
        same_files(whole, sub, names)
        d = report(rep)["distributed"]
        assert d["output"] == "pieces" and len(d["per_rank"]) == P, d
        assert all(q["slabs"] > q["attempts"] for q in d["per_rank"]), d["per_rank"]  # each attempt streamed
        reports.append(d)
    return reports


def coarse_pieces_equal():
    for P in (2, 3):
        coarse_pieces([SPHERE], ["--iso", 12.5, "--normals", "average"], P, (3 * PLANE, 7 * PLANE), "sphere")


def plate_halo_grows_streamed():
    nx, ny, nz = 33, 29, 40
    path = one_voxel_plate(os.path.join(D, "plate.raw"), nx, ny, nz)
    d = coarse_pieces([path, "--dims", nx, ny, nz], ["--iso", 0.55], 3, (4 * nx * ny * 4,), "plate")[0]
    assert d["attempts"] >= 2, d  # the halo grew: its planes were read again, streamed


def refusal():
    p = mpirun(2, "contour", SPHERE, "--iso", 12.5, "-q", "--memory-limit", 4 * PLANE, "-o",
               os.path.join(D, "x.vtp"), "--balance", expect=2)
    assert p.stderr.count("--memory-limit with --balance under mpirun") == 1, p.stderr
    assert not os.path.exists(os.path.join(D, "x.vtp"))


check("-np 2 and 3 --memory-limit: gathered file byte-identical to one process (isovalues, normals, coarsen)",
      gathered_equal)
check("-np 2 --memory-limit -o X.pvtp: pieces byte-identical to the pieces without a limit", pieces_equal)
check("-np 2 and 3 --coarsen --normals average -o X.pvtp, two limits: pieces byte-identical to no limit",
      coarse_pieces_equal)
check("-np 3 --coarsen -o X.pvtp, a plate that grows the halo: streamed pieces byte-identical to no limit",
      plate_halo_grows_streamed)
check("--memory-limit with --balance: refused by name, said once", refusal)
finish()
