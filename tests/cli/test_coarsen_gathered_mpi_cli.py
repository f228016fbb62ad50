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
(the plain contour's), and the ranks' together cover it. Skipped (77)
without mpirun or MPI."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import box_filtered_noise, check, finish, mpirun, report, require_mpi, run, tempdir  # noqa: E402

D = tempdir()
NX, NY, NZ = 33, 29, 40  # 39 voxel layers: 13 a rank at -np 3, halos of 8 first
NOISE = os.path.join(D, "noise.raw")
box_filtered_noise((NZ, NY, NX), 23).tofile(NOISE)
SRC = [NOISE, "--dims", NX, NY, NZ]
PLANE = NX * NY * 4
COUNTS = ("triangles_before", "triangles_after", "nonmanifold_edges", "nonmanifold_vertices", "boundary_edges")
require_mpi("contour", *SRC, "--iso", 0.5, "-o", os.path.join(D, "probe.vtp"), "-q")


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
    import numpy as np
    v = np.zeros((NZ, NY, NX), np.float32)
    rng = np.random.default_rng(5)
    v[:, 4:25, 16] = 0.75 + 0.25 * rng.random((NZ, 21))
    v[:, 4:25, 15] = 0.3 * rng.random((NZ, 21))
    v[:, 4:25, 17] = 0.3 * rng.random((NZ, 21))
    path = os.path.join(D, "plate.raw")
    v.tofile(path)
    src = [path, "--dims", NX, NY, NZ]
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
finish()
