"""`keymesh contour --coarsen` under `--memory-limit` and `mpirun` (issue 17).

Coarsening merges the crossings nearest one grid point; two slabs (or two
ranks) may hold crossings of the same grid point, so the slabs' fine points
are merged by their global edge keys first and the whole is coarsened as one
process coarsens it. Checked against the single in-memory process of the
same keymesh: the output file is byte-identical for several slab sizes, for
mpirun -np 1..4, with gradient or averaged normals and several isovalues, on
smoothed noise (many collapsed triangles and folds) and a real MRI volume
when installed. The report's counts are checked against the file read back.
Pieces (.pvtp) under --coarsen: test_coarsen_pieces_mpi_cli.py."""
import os
import shutil
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import box_filtered_noise, brainsmall_nrrd, check, finish, mpirun, report, run, tempdir  # noqa: E402

D = tempdir()
NX, NY, NZ = 41, 37, 29
NOISE = os.path.join(D, "noise.raw")
box_filtered_noise((NZ, NY, NX), 17).tofile(NOISE)
DIMS = ["--dims", NX, NY, NZ]
PLANE = NX * NY * 4


def read_ply_counts(path):
    with open(path, "rb") as f:
        head = f.read(4096).split(b"end_header")[0].decode()
    counts = {}
    for line in head.splitlines():
        if line.startswith("element"):
            _, name, n = line.split()
            counts[name] = int(n)
    return counts["vertex"], counts["face"]


def contour(out, *args, source=None, extra=()):
    src = [NOISE, *DIMS] if source is None else [source]
    run("contour", *src, "-o", out, "--coarsen", "-q", *args, *extra)
    return open(out, "rb").read()


CASES = [
    ["--iso", 0.5, "--threads", 2],
    ["--iso", 0.5, "--iso", 0.47, "--normals", "gradient", "--curvature"],
    ["--iso", 0.52, "--normals", "average"],
]


def streamed_equals_in_memory():
    for i, args in enumerate(CASES):
        ref = contour(os.path.join(D, f"mem{i}.ply"), *args, extra=["--report", os.path.join(D, f"mem{i}.json")])
        r = report(os.path.join(D, f"mem{i}.json"))
        points, faces = read_ply_counts(os.path.join(D, f"mem{i}.ply"))
        assert r["points"] == points and r["cells"] == faces == r["triangles_after"], r
        assert r["triangles_before"] > faces, r
        for planes in (4, 7, NZ):
            out = os.path.join(D, f"stream{i}_{planes}.ply")
            rep = out + ".json"
            got = contour(out, *args, extra=["--memory-limit", planes * PLANE, "--report", rep])
            assert got == ref, f"{args} --memory-limit {planes} planes: differs from in-memory"
            s = report(rep)
            assert s["stream"]["slabs"] > 1 or planes == NZ, s["stream"]
            assert s["triangles_before"] == r["triangles_before"], (s, r)
            assert s["nonmanifold_edges"] == r["nonmanifold_edges"], (s, r)


def distributed_equals_single_process():
    if not shutil.which("mpirun"):
        print("(no mpirun: distributed part skipped)")
        return
    for i, args in enumerate(CASES):
        ref = open(os.path.join(D, f"mem{i}.ply"), "rb").read() if os.path.exists(os.path.join(D, f"mem{i}.ply")) \
            else contour(os.path.join(D, f"mem{i}.ply"), *args)
        r = report(os.path.join(D, f"mem{i}.json")) if os.path.exists(os.path.join(D, f"mem{i}.json")) else None
        for P in (1, 2, 3, 4):
            out = os.path.join(D, f"mpi{i}_{P}.ply")
            rep = out + ".json"
            mpirun(P, "contour", NOISE, *DIMS, "-o", out, "--coarsen", "-q", "--report", rep, *args)
            assert open(out, "rb").read() == ref, f"{args} -np {P}: differs from one process"
            s = report(rep)
            points, faces = read_ply_counts(out)
            assert s["points"] == points and s["cells"] == faces == s["triangles_after"], s
            if r:
                assert s["triangles_before"] == r["triangles_before"], (s, r)


def real_volume():
    nrrd = brainsmall_nrrd(D)
    if nrrd is None:
        return
    ref = contour(os.path.join(D, "brain.ply"), "--iso", 37.3, source=nrrd)
    got = contour(os.path.join(D, "brain_s.ply"), "--iso", 37.3, source=nrrd, extra=["--memory-limit", 8 * 128 * 128])
    assert got == ref, "brainsmall.den streamed coarsening differs"
    if shutil.which("mpirun"):
        out = os.path.join(D, "brain_mpi.ply")
        mpirun(3, "contour", nrrd, "--iso", 37.3, "-o", out, "--coarsen", "-q")
        assert open(out, "rb").read() == ref, "brainsmall.den -np 3 coarsening differs"


check("--coarsen --memory-limit: byte-identical to in-memory (3 slab sizes, normals, curvature, 2 isovalues)",
      streamed_equals_in_memory)
check("mpirun -np 1..4 --coarsen: gathered file byte-identical to one process; report counts = file",
      distributed_equals_single_process)
check("brainsmall.den iso 37.3: streamed and -np 3 coarsening byte-identical", real_volume)
finish()
