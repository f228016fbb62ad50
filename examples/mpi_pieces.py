"""MPI pieces: `mpirun -np 2 keymesh contour` splits a volume into slabs, one per rank.

    volume.nrrd  ->  rank 0: planes 0..k   contours its slab with the whole grid's   ->  pieces.pvtp
                     rank 1: planes k..n   edge keys; the ranks number the points        + one .vtp
                                           of the plane they share by key (no search)    piece per rank

    -o gathered.vtp instead: rank 0 gathers the whole mesh, the same bytes one process writes.

Checks: the gathered file equals the one-process file byte for byte; the pieces, read back as
one mesh (keymesh.read welds them by their GlobalPointIds), give the same points and triangles.
Exits 77 (skipped) where mpirun is missing or cannot start programs, or keymesh lacks MPI.
Run: KEYMESH=build/keymesh PYTHONPATH=build/python /usr/bin/python3 examples/mpi_pieces.py
"""
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

import keymesh

KEYMESH = os.environ.get("KEYMESH") or shutil.which("keymesh") or "keymesh"
MPIRUN = shutil.which("mpirun")
if not MPIRUN:
    print("skipped: no mpirun (Debian: openmpi-bin)")
    sys.exit(77)


def mpirun(ranks, *args):
    """`mpirun -np ranks` of `args`; one thread per rank (ranks may share cores)."""
    cmd = [MPIRUN, "--oversubscribe", "-np", str(ranks)] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])
    env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_MCA_btl_vader_single_copy_mechanism="none")
    return subprocess.run(cmd + list(args), capture_output=True, text=True, env=env, timeout=300)


if mpirun(2, shutil.which("true") or "/bin/true").returncode != 0:
    print("skipped: mpirun cannot start programs here")
    sys.exit(77)

folder = tempfile.mkdtemp(prefix="keymesh-mpi-")
volume = os.path.join(folder, "volume.nrrd")
i, j, k = np.indices((48, 40, 36), dtype=np.float32)
keymesh.write(np.sqrt((i - 23.5) ** 2 + (j - 19.5) ** 2 + (k - 17.5) ** 2), volume)  # a ball's distance field
contour = ["contour", volume, "--iso", "15.5", "-q"]

whole = os.path.join(folder, "whole.vtp")
subprocess.run([KEYMESH, *contour, "-o", whole], check=True)
p = mpirun(2, KEYMESH, *contour, "-o", os.path.join(folder, "gathered.vtp"))
if p.returncode != 0 and "built without MPI" in p.stderr:
    print("skipped: keymesh was built without MPI (Debian: libopenmpi-dev, then rebuild)")
    sys.exit(77)
assert p.returncode == 0, p.stderr
assert open(os.path.join(folder, "gathered.vtp"), "rb").read() == open(whole, "rb").read()

pieces = os.path.join(folder, "pieces.pvtp")
p = mpirun(2, KEYMESH, *contour, "-o", pieces)
assert p.returncode == 0, p.stderr
print(sorted(os.listdir(folder)))
merged, reference = keymesh.read(pieces), keymesh.read(whole)
assert np.array_equal(merged.points, reference.points), "pieces merged: other points"
assert np.array_equal(merged.cells, reference.cells), "pieces merged: other triangles"
assert keymesh.check(merged)["closed_manifold"]
print(f"2 pieces -> {len(merged.points)} points, {len(merged.cells)} triangles, as one process")
shutil.rmtree(folder)
