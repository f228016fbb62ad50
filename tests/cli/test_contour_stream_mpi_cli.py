"""`mpirun -np P keymesh contour --memory-limit SIZE`: each rank streams its
own planes (issue 36).

A rank reads its slab of planes in sub-slabs that fit the limit and merges
them by edge key, which gives the piece one read of the whole slab gives; the
rest of the distributed contour is unchanged. Checked: with -np 2 and 3 the
gathered file is byte-identical to one process (two isovalues; gradient
normals and curvature with their ghost planes; averaged normals; coarsened
with averaged normals), the .pvtp pieces are byte-identical to the pieces
written without a limit, and the two combinations that hold a rank's
planes whole (--balance; --coarsen into pieces) are refused by name, said
once."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, mpirun, report, require_mpi, run, tempdir  # noqa: E402

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


def refused(*args, says):
    p = mpirun(2, "contour", SPHERE, "--iso", 12.5, "-q", "--memory-limit", 4 * PLANE, *args, expect=2)
    assert p.stderr.count(says) == 1, p.stderr


def refusals():
    refused("-o", os.path.join(D, "x.vtp"), "--balance", says="--memory-limit with --balance under mpirun")
    refused("-o", os.path.join(D, "x.pvtp"), "--coarsen", says="--memory-limit with --coarsen and .pvtp pieces")
    assert not os.path.exists(os.path.join(D, "x.pvtp"))


check("-np 2 and 3 --memory-limit: gathered file byte-identical to one process (isovalues, normals, coarsen)",
      gathered_equal)
check("-np 2 --memory-limit -o X.pvtp: pieces byte-identical to the pieces without a limit", pieces_equal)
check("--memory-limit with --balance, or with --coarsen into pieces: refused by name, said once", refusals)
finish()
