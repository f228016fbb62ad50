"""`mpirun -np P keymesh labels` (issue 18): every rank reads and contours its
rows of the volume, the ranks share their distinct labels and voxel counts,
rank 0 gathers the pieces, merges them by key, smooths and writes one file.
The reference is the single-process in-memory run of the same keymesh (its
surfaces are checked against numpy and skimage in test_labels_cli.py): the
file must be byte-identical for P = 1..4, both methods, one network and
--per-label, with and without smoothing, also with --memory-limit on every
rank and with more ranks than a thin volume has planes (a rank with no rows).
.pvtp pieces (nothing gathered) are test_labels_pieces_mpi_cli.py's. Skipped (77)
without mpirun or MPI."""
import os
import shutil
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, mpirun, report, run, tempdir  # noqa: E402

MPIRUN = shutil.which("mpirun")
if not MPIRUN:
    print("skipped: no mpirun (install openmpi-bin and libopenmpi-dev)")
    sys.exit(77)
try:
    import numpy as np
except ImportError as e:
    print(f"skipped: {e}")
    sys.exit(77)


D = tempdir()
launcher = mpirun(2, expect=None, program=shutil.which("true") or "/bin/true")
if launcher.returncode != 0:
    print(f"skipped: mpirun -np 2 true fails here (exit {launcher.returncode}): {launcher.stderr.strip()[:400]}")
    sys.exit(77)

rng = np.random.default_rng(9)
SHAPE = (9, 10, 12)  # x, y, z
noise = rng.integers(0, 4, size=SHAPE)
boxes = np.zeros(SHAPE, np.int16)
boxes[1:6, 2:8, 1:8] = 5
boxes[3:8, 1:6, 5:11] = 9
MIX = os.path.join(D, "mix.raw")
vol = np.where(rng.random(SHAPE) < 0.5, noise, boxes).astype(np.int16)
with open(MIX, "wb") as f:
    f.write(vol.tobytes(order="F"))  # x fastest
RAW = ["--dims", *SHAPE, "--type", "int16"]
probe = mpirun(2, "labels", MIX, *RAW, "-o", os.path.join(D, "probe.vtp"), "-q", expect=None)
if probe.returncode != 0 and "built without MPI" in probe.stderr:
    print("skipped: keymesh was built without MPI (install libopenmpi-dev and rebuild)")
    sys.exit(77)


def same_as_one_process(path, raw, args, ranks=(1, 2, 3, 4), extra=()):
    def fn():
        ref = os.path.join(D, "ref.vtp")
        run("labels", path, *raw, "-o", ref, *args, "-q")
        with open(ref, "rb") as f:
            expected = f.read()
        for P in ranks:
            out, rep = os.path.join(D, f"p{P}.vtp"), os.path.join(D, f"p{P}.json")
            mpirun(P, "labels", path, *raw, "-o", out, *args, *extra, "-q", "--report", rep)
            with open(out, "rb") as f:
                assert f.read() == expected, f"mpirun -np {P} {args}: not byte-identical"
            r = report(rep)
            if P > 1:
                per_rank = r["distributed"]["per_rank"]
                assert len(per_rank) == P and sum(q["rows"] for q in per_rank) == SHAPE_ROWS[path], per_rank
    return fn


SHAPE_ROWS = {MIX: SHAPE[2] + 2}
for method in ("surfacenets", "discrete-mc"):
    for per_label in ([], ["--per-label"]):
        for smooth in ("0", "3"):
            args = ["--method", method, *per_label, "--smooth", smooth]
            check(f"mpirun -np 1..4 {' '.join(args)}: byte-identical to one process",
                  same_as_one_process(MIX, RAW, args))
    # Each rank streams its rows too: 1 row per slab (two samples and two
    # index planes of 11 x 12 plus one more of each).
    plane = SHAPE[0] * SHAPE[1] * 2 + (SHAPE[0] + 2) * (SHAPE[1] + 2) * 2
    check(f"{method}: mpirun -np 3 with --memory-limit (one row per slab on every rank): byte-identical",
          same_as_one_process(MIX, RAW, ["--method", method, "--per-label"], (3,), ["--memory-limit", 3 * plane]))

# One plane: three padded rows over four ranks, one of them with none.
THIN = os.path.join(D, "thin.raw")
with open(THIN, "wb") as f:
    f.write(vol[:, :, 5:6].tobytes(order="F"))
SHAPE_ROWS[THIN] = 3
for method in ("surfacenets", "discrete-mc"):
    check(f"{method}: a one-plane volume on 4 ranks (a rank without rows): byte-identical",
          same_as_one_process(THIN, ["--dims", SHAPE[0], SHAPE[1], 1, "--type", "int16"], ["--method", method], (4,)))


def bad_label_refused():
    out = os.path.join(D, "bad.vtp")
    p = mpirun(3, "labels", MIX, *RAW, "-o", out, "--labels", "77", expect=1)
    assert "77" in p.stderr and "mix.raw" in p.stderr, p.stderr
    assert not os.path.exists(out)


check("a label the volume does not hold is refused by name on every rank, no output", bad_label_refused)

finish()
