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
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (boxes_in_noise, check, finish, mpirun, report, require_mpi, require_numpy, run,  # noqa: E402
                    tempdir, write_raw)

np = require_numpy()
D = tempdir()
SHAPE = (9, 10, 12)  # x, y, z
vol = boxes_in_noise(SHAPE, 9, [(5, np.s_[1:6, 2:8, 1:8]), (9, np.s_[3:8, 1:6, 5:11])], 0.5)
MIX = write_raw(os.path.join(D, "mix.raw"), vol)
RAW = ["--dims", *SHAPE, "--type", "int16"]
require_mpi("labels", MIX, *RAW, "-o", os.path.join(D, "probe.vtp"), "-q")


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
