"""`mpirun -np P keymesh contour ... --coarsen -o OUT.vtp` (one gathered
file, not .pvtp pieces): every rank coarsens its own voxel layers with a
halo, as for pieces (test_coarsen_pieces_mpi_cli.py), and only the coarse
pieces are gathered on rank 0, which puts them together by global id and
writes them. Rank 0 no longer holds the whole fine mesh.

Checked against the single-process run of the same keymesh: the gathered
file is byte-identical (.vtp and .ply) at -np 2 and 3 for smoothed noise
with one isovalue, averaged normals, two isovalues with gradient normals and
curvature, under --memory-limit and --balance, and for a plate one voxel
thick that makes the halo grow; the report's counts (triangles before and
after, non-manifold edges and vertices, boundary edges) are one process's,
it says "output": "gathered" with a "gather" stage, and every rank's entry
has fine_points_held: rank 0's is well below the whole fine mesh's points
(the plain contour's), and the ranks' together cover it.

`keymesh labels` into one file takes the same road (every rank makes,
smooths and coarsens its rows plus halo rows as for .pvtp pieces; only the
finished shares are gathered): with --coarsen (surface nets and discrete MC,
per label or the network, smoothed) and with --history the file is
byte-identical to one process at -np 2 and 3, and no rank's share holds
the whole mesh's points. Skipped (77) without mpirun or MPI."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (box_filtered_noise, boxes_in_noise, check, finish, mpirun, report, write_plate,  # noqa: E402
                    require_mpi, run, tempdir, write_raw)

D = tempdir()
NX, NY, NZ = 33, 29, 40  # 39 voxel layers: 13 a rank at -np 3, halos of 8 first
NOISE = os.path.join(D, "noise.raw")
box_filtered_noise((NZ, NY, NX), 23).tofile(NOISE)
SRC = [NOISE, "--dims", NX, NY, NZ]
PLANE = NX * NY * 4
COUNTS = ("triangles_before", "triangles_after", "nonmanifold_edges", "nonmanifold_vertices", "boundary_edges")
require_mpi("contour", *SRC, "--iso", 0.5, "-o", os.path.join(D, "probe.vtp"), "-q")
import numpy as np  # noqa: E402  (box_filtered_noise above has required it)


def read(path):
    with open(path, "rb") as f:
        return f.read()


def fine_points(src, args):
    """The plain contour's points: the whole fine mesh the coarsening starts from."""
    rep = os.path.join(D, "fine.json")
    run("contour", *src, *[a for a in args if a != "--curvature"], "-o", os.path.join(D, "fine.vtp"), "-q",
        "--report", rep)
    return report(rep)["points"]


def gathered_equals_one_process(src, args, ext=".vtp", ranks=(2, 3), extra=(), name="case"):
    one = os.path.join(D, f"one_{name}{ext}")
    run("contour", *src, *args, "--coarsen", "-o", one, "-q", "--report", one + ".json")
    ref = report(one + ".json")
    assert ref["triangles_before"] > ref["triangles_after"] > 100, ref
    fine = fine_points(src, args)
    for P in ranks:
        out = os.path.join(D, f"g{P}_{name}{ext}")
        mpirun(P, "contour", *src, *args, *extra, "--coarsen", "-o", out, "-q", "--report", out + ".json")
        assert read(out) == read(one), f"{name} {args} {extra} -np {P}: gathered file differs from one process"
        r = report(out + ".json")
        d = r["distributed"]
        assert d["output"] == "gathered" and d["ranks"] == P and len(d["per_rank"]) == P, d
        assert "gather" in r["seconds"], r["seconds"]
        assert r["points"] == ref["points"] and r["cells"] == ref["cells"], (r["points"], r["cells"])
        for key in COUNTS:
            assert r[key] == ref[key], (key, r[key], ref[key])
        held = [q["fine_points_held"] for q in d["per_rank"]]
        # Rank 0 holds its layers and a halo, not the whole fine mesh as the
        # gather of the fine pieces did; together the ranks hold all of it.
        assert 0 < held[0] < 0.85 * fine, (held, fine)
        assert sum(held) >= fine, (held, fine)
        print(f"{name} -np {P}: fine points held per rank {held} of {fine}; halo {d['halo_layers']}")
    return d


CASES = [
    ("iso", ["--iso", 0.5], ".vtp"),
    ("average", ["--iso", 0.52, "--normals", "average"], ".ply"),
    ("two_gradient", ["--iso", 0.5, "--iso", 0.47, "--normals", "gradient", "--curvature"], ".vtp"),
]
for name, args, ext in CASES:
    check(f"smoothed noise {' '.join(map(str, args))} -> {ext}: -np 2, 3 gathered byte-identical to one process",
          lambda name=name, args=args, ext=ext: gathered_equals_one_process(SRC, args, ext, name=name))

check("--memory-limit 4 planes, averaged normals: -np 2, 3 gathered byte-identical to one process",
      lambda: gathered_equals_one_process(SRC, ["--iso", 0.52, "--normals", "average"],
                                          extra=("--memory-limit", 4 * PLANE), name="limit"))
check("--balance, two isovalues: -np 3 gathered byte-identical to one process",
      lambda: gathered_equals_one_process(SRC, ["--iso", 0.5, "--iso", 0.47], ranks=(3,), extra=("--balance",),
                                          name="balance"))


def plate():
    """A plate one voxel thick spanning every slab (test_coarsen_pieces_mpi_cli.py's):
    the halo grows to the whole volume, and the file is still one process's."""
    src = write_plate(os.path.join(D, "plate.raw"))
    one = os.path.join(D, "plate_one.vtp")
    run("contour", *src, "--iso", 0.55, "--coarsen", "-o", one, "-q")
    out = os.path.join(D, "plate_3.vtp")
    mpirun(3, "contour", *src, "--iso", 0.55, "--coarsen", "-o", out, "-q", "--report", out + ".json")
    assert read(out) == read(one), "plate -np 3: gathered file differs from one process"
    assert report(out + ".json")["distributed"]["attempts"] >= 2


check("a one-voxel plate (the halo grows): -np 3 gathered byte-identical to one process", plate)


def unwritable_output_fails_once():
    p = mpirun(3, "contour", *SRC, "--iso", 0.5, "--coarsen", "-o", os.path.join(D, "nowhere", "x.vtp"), expect=1)
    said = [line for line in p.stderr.splitlines() if line.startswith("keymesh")]
    assert len(said) == 1 and "nowhere" in said[0], p.stderr


check("an output rank 0 cannot write: one message, exit 1, no hang", unwritable_output_fails_once)

LSHAPE = (21, 19, 26)  # x, y, z: 28 padded rows
LABELS = write_raw(os.path.join(D, "labels.raw"), boxes_in_noise(
    LSHAPE, 11, [(5, np.s_[2:14, 3:15, 2:18]), (9, np.s_[8:19, 2:12, 9:24]), (7, np.s_[4:9, 10:17, 14:25])], 0.15))
LRAW = ["--dims", *LSHAPE, "--type", "int16"]


def labels_gathered(args):
    def fn():
        one = os.path.join(D, "labels_one.vtp")
        run("labels", LABELS, *LRAW, *args, "-o", one, "-q", "--report", one + ".json")
        ref = report(one + ".json")
        assert ref["cells"] > 500, ref
        for P in (2, 3):
            out = os.path.join(D, f"labels_{P}.vtp")
            mpirun(P, "labels", LABELS, *LRAW, *args, "-o", out, "-q", "--report", out + ".json")
            assert read(out) == read(one), f"labels {args} -np {P}: gathered file differs from one process"
            r = report(out + ".json")
            d = r["distributed"]
            assert d["output"] == "gathered" and len(d["per_rank"]) == P, d
            assert r["points"] == ref["points"] and r["cells"] == ref["cells"] and r["pairs"] == ref["pairs"]
            assert "soup_points" not in r and "triangles_before" not in r, r  # never whole on one rank
            shares = [q["points"] for q in d["per_rank"]]
            assert max(shares) < ref["points"] and sum(q["triangles"] for q in d["per_rank"]) == ref["cells"], shares
    return fn


for args in (["--coarsen"], ["--coarsen", "--per-label", "--smooth", "3"],
             ["--method", "discrete-mc", "--coarsen"], ["--method", "discrete-mc", "--per-label", "--coarsen"],
             ["--history"]):
    check(f"labels {' '.join(args)}: -np 2, 3 gathered byte-identical to one process, shared by the ranks",
          labels_gathered(args))
finish()
