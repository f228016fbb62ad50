#!/usr/bin/env python3
"""Proves that a change left keymesh's outputs alone: runs the main commands
and formats with two builds and compares every output file byte for byte.

    python3 scripts/same_outputs.py --before /path/to/old/keymesh --after build/keymesh [--keep DIR] [--only REGEX]

Inputs are built-in (`keymesh generate`) or from Debian packages the Makefile
installs (brainsmall.den from libvolpack1-dev, ch2.nii.gz from mricron-data).
Each case runs with --threads 1 and --threads 2 under the new build too, so
the comparison also shows thread-count independence. A directory output
(--format precomputed) must hold the same file names, each byte for byte.
--only runs the cases whose name matches REGEX (with the cases whose output
they read). Exits 1 and lists the outputs that differ; 0 when every one is
identical.
"""
import argparse
import filecmp
import os
import re
import shutil
import subprocess
import sys
import tempfile

BRAIN = "/usr/share/doc/libvolpack1-dev/examples/brainsmall.den"
HEAD = "/usr/share/mricron/templates/ch2.nii.gz"
AAL = "/usr/share/mricron/templates/aal.nii.gz"
# Neuroglancer multi-resolution output: -o names a directory (DIR/chunks too),
# compared file by file.
NG_GRID = "--format precomputed --lods 3 --chunk-shape 32 32 32"

# (name, arguments after the command name; {in:NAME} is an input, {out} the output path)
CASES = [
    ("sphere-ply", "contour {in:s96.vti} -o {out}.ply --iso 46.3"),
    ("sphere-vtp-avg", "contour {in:s96.vti} -o {out}.vtp --iso 46.3 --normals average"),
    ("sphere-grad-curv", "contour {in:s96.vti} -o {out}.vtp --iso 46.3 --normals gradient --curvature"),
    ("sphere-isos", "contour {in:s96.vti} -o {out}.vtp --iso 10.5 --iso 30.2 --iso 47.001 --normals average"),
    ("sphere-coarsen", "contour {in:s96.vti} -o {out}.vtp --iso 46.3 --coarsen --normals average"),
    ("sphere-sort", "contour {in:s96.vti} -o {out}.ply --iso 46.3 --weld keyreduce-sort"),
    ("sphere-vweld", "contour {in:s96.vti} -o {out}.ply --iso 46.3 --weld vertexweld --normals average"),
    ("sphere-obj", "contour {in:s96.vti} -o {out}.obj --iso 46.3"),
    ("sphere-stl", "contour {in:s96.vti} -o {out}.stl --iso 46.3"),
    ("sphere-stream", "contour {in:s96.nrrd} -o {out}.vtp --iso 46.3 --normals gradient --curvature --memory-limit 1M"),
    ("brain-den", f"contour {BRAIN} -o {{out}}.vtp --iso 37.3 --normals average"),
    ("brain-den-coarsen", f"contour {BRAIN} -o {{out}}.ply --iso 37.3 --coarsen"),
    ("brain-den-coarsen-sort", f"contour {BRAIN} -o {{out}}.ply --iso 37.3 --coarsen --weld keyreduce-sort"),
    ("head-nii-coarsen-isos", f"contour {HEAD} -o {{out}}.vtp --iso 90.5 --iso 40.5 --coarsen --normals gradient --curvature"),
    ("head-nii", f"contour {HEAD} -o {{out}}.vtp --iso 90.5 --iso 40.5 --normals gradient"),
    ("head-nii-curv", f"contour {HEAD} -o {{out}}.vtp --iso 90.5 --curvature --no-scalars"),
    ("head-nii-coarsen-grad", f"contour {HEAD} -o {{out}}.vtp --iso 90.5 --coarsen --normals gradient"),
    ("head-nii-coarsen-curv", f"contour {HEAD} -o {{out}}.vtp --iso 90.5 --coarsen --curvature --no-scalars"),
    ("head-nrrd-stream", "contour {in:head.nrrd} -o {out}.ply --iso 90.5 --memory-limit 4M"),
    ("head-nii-positions", "contour " + HEAD + " -o {out}.ply --iso 90.5 --iso 40.5 --no-scalars"),
    ("head-nii-coarsen-positions", "contour " + HEAD + " -o {out}.ply --iso 90.5 --iso 40.5 --coarsen --no-scalars"),
    ("tets", "tetrahedralize {in:s24.vti} -o {out}.vtu"),
    ("tets24", "tetrahedralize {in:s24.vti} -o {out}.vtu --scheme 24"),
    ("hexes5", "tetrahedralize {in:hexes.vtk} -o {out}.vtu"),
    ("hexes24", "tetrahedralize {in:hexes.vtk} -o {out}.vtu --scheme 24"),
    ("hexes24-vweld", "tetrahedralize {in:hexes.vtk} -o {out}.vtu --scheme 24 --weld vertexweld"),
    ("tets24-vweld", "tetrahedralize {in:s24.vti} -o {out}.vtu --scheme 24 --weld vertexweld"),
    ("tet-contour", "contour {in:tets} -o {out}.vtp --iso 9.3 --normals average"),
    ("tet-contour-vweld", "contour {in:tets} -o {out}.vtp --iso 9.3 --normals average --weld vertexweld"),
    ("subdivide", "subdivide {in:tets} -o {out}.vtu"),
    ("subdivide-vweld", "subdivide {in:tets} -o {out}.vtu --weld vertexweld"),
    ("subdivide-surface", "subdivide {in:sphere-vtp-avg} -o {out}.vtp"),
    ("dual", "dual {in:sphere-ply} -o {out}.vtp"),
    ("convert-vtk", "convert {in:tets} -o {out}.vtk"),
    ("convert-vtp", "convert {in:sphere-vtp-avg} -o {out}.ply"),
    ("convert-glb", "convert {in:sphere-vtp-avg} -o {out}.glb"),
    ("convert-vti", "convert {in:s96.nrrd} -o {out}.vti"),
    ("pipeline", "pipeline {in:s96.vti} -o {out}.vtp --iso 46.3 --coarsen --subdivide 1 --dual"),
    ("labels-nets", f"labels {AAL} -o {{out}}.vtp"),
    ("labels-nets-raw", f"labels {AAL} -o {{out}}.ply --smooth 0"),
    ("labels-mc", f"labels {AAL} -o {{out}}.vtp --method discrete-mc --labels 3,17,40"),
    ("labels-per-label", f"labels {AAL} -o {{out}}.vtp --per-label --labels 5,6,7"),
    ("labels-ng", f"labels {AAL} -o {{out}}.ng {NG_GRID}"),
    ("labels-ng-sharded", f"labels {AAL} -o {{out}}.ng {NG_GRID} --sharded"),
    ("labels-ng-balls", f"labels {{in:balls.nrrd}} -o {{out}}.ng {NG_GRID}"),
    ("labels-ng-balls-sharded", f"labels {{in:balls.nrrd}} -o {{out}}.ng {NG_GRID} --sharded"),
    ("mpi-contour", "mpirun:2 contour {in:s96.vti} -o {out}.vtp --iso 46.3 --normals gradient"),
    ("mpi-contour-3", f"mpirun:3 contour {HEAD} -o {{out}}.ply --iso 90.5 --balance"),
    ("contour-glb", f"contour {HEAD} -o {{out}}.glb --iso 90.5 --normals average"),
    ("dicom", "contour {in:series} -o {out}.vtp --iso 46.3 --normals gradient"),
    ("dicom-stream", "contour {in:series} -o {out}.ply --iso 46.3 --memory-limit 40K"),
    ("zarr", "contour {in:s48.zarr} -o {out}.vtp --iso 20.3 --normals gradient"),
    ("zarr-stream", "contour {in:s48.zarr} -o {out}.ply --iso 20.3 --memory-limit 40K"),
]

# A DICOM series (tests/dicom_series.py, pydicom) and a Zarr array (zlib
# chunks, one left to fill_value) of a 48^3 distance field: Debian's
# python3, which has pydicom and zarr. And a label map (tests/kmtest.py's
# write_label_nrrd) of touching balls, one reaching the border, and a slab of
# two-label noise, which crosses every chunk face: 70 x 60 x 50 uint8.
FOLDER_INPUTS = """
import os, sys
import numpy as np, numcodecs, zarr
sys.path.insert(0, os.path.join(sys.argv[1], "tests"))
from dicom_series import write_dicom_series
from kmtest import write_label_nrrd
x, y, z = np.meshgrid(np.arange(70), np.arange(60), np.arange(50), indexing="ij")
balls = np.zeros(x.shape, np.uint8)
for label, (cx, cy, cz, r) in enumerate([(20, 20, 20, 14), (38, 25, 22, 11), (60, 50, 40, 15), (35, 45, 30, 9)], 1):
    balls[(x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2 <= r * r] = label
slab = (z >= 36) & (z < 41)
balls[slab] = np.where(np.random.default_rng(7).random(balls[slab].shape) < 0.5, 5, 6)
write_label_nrrd(os.path.join(sys.argv[2], "balls.nrrd"), balls)
z, y, x = np.mgrid[0:48, 0:48, 0:48]
field = np.sqrt((x - 24.0) ** 2 + (y - 24.0) ** 2 + (z - 24.0) ** 2)
write_dicom_series(os.path.join(sys.argv[2], "series"), (field * 2).astype(np.int16), slope=0.5, intercept=0)
a = zarr.open(os.path.join(sys.argv[2], "s48.zarr"), mode="w", shape=field.shape, chunks=(10, 16, 20), dtype="<f4",
              compressor=numcodecs.Zlib(level=1), fill_value=30)
a[:] = field.astype(np.float32)
os.remove(os.path.join(sys.argv[2], "s48.zarr", "0.0.0"))
"""


MPIRUN = shutil.which("mpirun")


def write_hex_grid(path, n=(5, 4, 3)):
    """A legacy .vtk grid of VTK_HEXAHEDRON cells with a jittered point field
    and a cell field, written here (no keymesh involved), so that the
    unstructured-hexahedra paths of tetrahedralize are compared too."""
    nx, ny, nz = n
    pts = [(i + 0.1 * ((i * 7 + j * 3 + k) % 5), j + 0.05 * ((i + 2 * j + 5 * k) % 3), k * 1.5)
           for k in range(nz) for j in range(ny) for i in range(nx)]
    pid = lambda i, j, k: (k * ny + j) * nx + i
    cells = []
    for k in range(nz - 1):
        for j in range(ny - 1):
            for i in range(nx - 1):
                cells.append([pid(i, j, k), pid(i + 1, j, k), pid(i + 1, j + 1, k), pid(i, j + 1, k),
                              pid(i, j, k + 1), pid(i + 1, j, k + 1), pid(i + 1, j + 1, k + 1), pid(i, j + 1, k + 1)])
    with open(path, "w") as f:
        f.write("# vtk DataFile Version 3.0\nhexes\nASCII\nDATASET UNSTRUCTURED_GRID\n")
        f.write(f"POINTS {len(pts)} float\n" + "".join(f"{x} {y} {z}\n" for x, y, z in pts))
        f.write(f"CELLS {len(cells)} {9 * len(cells)}\n" + "".join("8 " + " ".join(map(str, c)) + "\n" for c in cells))
        f.write(f"CELL_TYPES {len(cells)}\n" + "12\n" * len(cells))
        f.write(f"POINT_DATA {len(pts)}\nSCALARS density float 1\nLOOKUP_TABLE default\n")
        f.write("".join(f"{(x - 2) ** 2 + y * y + z}\n" for x, y, z in pts))
        f.write(f"CELL_DATA {len(cells)}\nSCALARS cell_id float 1\nLOOKUP_TABLE default\n")
        f.write("".join(f"{c}\n" for c in range(len(cells))))


def run(keymesh, args, check=True):
    """Runs keymesh; arguments that start with `mpirun:P` run it as P MPI ranks."""
    cmd = [keymesh]
    env = None
    if args and args[0].startswith("mpirun:"):
        ranks = args.pop(0).split(":")[1]
        cmd = [MPIRUN, "--oversubscribe", "-np", ranks, keymesh]
        if os.geteuid() == 0:
            cmd.insert(1, "--allow-run-as-root")
        env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_MCA_btl_vader_single_copy_mechanism="none")
    return subprocess.run(cmd + args, check=check, capture_output=True, text=True, env=env,
                          stdin=subprocess.DEVNULL)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--before", required=True)
    ap.add_argument("--after", required=True)
    ap.add_argument("--keep", help="write outputs here instead of a temporary folder")
    ap.add_argument("--only", help="run only the cases whose name matches this regular expression")
    a = ap.parse_args()
    if not MPIRUN:
        print("note: no mpirun, the mpirun: cases are left out")
        CASES[:] = [c for c in CASES if not c[1].startswith("mpirun:")]
    if a.only:
        CASES[:] = selected_cases(a.only)
    tmp = a.keep or tempfile.mkdtemp(prefix="keymesh-same-")
    os.makedirs(tmp, exist_ok=True)
    try:
        return compare_outputs(a, tmp)
    finally:
        if not a.keep:  # 1.3 GB a run: left in /tmp, a day of runs filled the disk
            shutil.rmtree(tmp, ignore_errors=True)


def selected_cases(pattern):
    """The cases matching pattern, and those whose outputs they read ({in:CASE}), in CASES' order."""
    names = {name for name, _ in CASES if re.search(pattern, name)}
    templates = dict(CASES)
    pending = list(names)
    while pending:
        for key in [k.split("}")[0] for k in templates[pending.pop()].split("{in:")[1:]]:
            if key in templates and key not in names:
                names.add(key)
                pending.append(key)
    return [c for c in CASES if c[0] in names]


def files_under(top):
    """Paths of every file below the directory top, relative to it."""
    return sorted(os.path.relpath(os.path.join(root, f), top) for root, _, fs in os.walk(top) for f in fs)


def same_output(a, b):
    """A file byte for byte; a directory (--format precomputed): the same
    file names, every file byte for byte."""
    if not os.path.isdir(a):
        return not os.path.isdir(b) and filecmp.cmp(a, b, shallow=False)
    names = files_under(a)
    if not os.path.isdir(b) or names != files_under(b):
        return False
    return bool(names) and all(filecmp.cmp(os.path.join(a, n), os.path.join(b, n), shallow=False) for n in names)


def compare_outputs(a, tmp):
    inputs = os.path.join(tmp, "inputs")
    os.makedirs(inputs, exist_ok=True)
    run(a.before, ["generate", "sphere", "--size", "96", "-o", os.path.join(inputs, "s96.vti"), "-q"])
    run(a.before, ["convert", os.path.join(inputs, "s96.vti"), "-o", os.path.join(inputs, "s96.nrrd"), "-q"])
    run(a.before, ["convert", HEAD, "-o", os.path.join(inputs, "head.nrrd"), "-q"])
    write_hex_grid(os.path.join(inputs, "hexes.vtk"))
    run(a.before, ["generate", "sphere", "--size", "24", "-o", os.path.join(inputs, "s24.vti"), "-q"])
    subprocess.run(["/usr/bin/python3", "-c", FOLDER_INPUTS, os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                    inputs], check=True)
    produced = {}  # (case, build) -> output file, for cases whose output is a later case's input
    differ = []
    compared = 0
    for name, template in CASES:
        suffix = template.split("{out}")[1].split()[0]
        outs = {}
        for build, exe, threads in (("before", a.before, "2"), ("after", a.after, "1"), ("after2", a.after, "2")):
            args = template
            for key in [k.split("}")[0] for k in template.split("{in:")[1:]]:
                path = produced[(key, build)] if (key, build) in produced else os.path.join(inputs, key)
                args = args.replace("{in:" + key + "}", path)
            outs[build] = os.path.join(tmp, f"{name}.{build}") + suffix
            args = args.replace("{out}" + suffix, outs[build]).split()
            args += ["--threads", threads, "-q"]
            r = run(exe, args, check=False)
            if r.returncode != 0:
                print(f"FAIL  {name} ({build}): exit {r.returncode}: {r.stderr.strip()}")
                differ.append(f"{name} ({build})")
                break
            produced[(name, build)] = outs[build]
        else:
            for build in ("after", "after2"):
                compared += 1
                same = same_output(outs["before"], outs[build])
                print(f"{'same ' if same else 'DIFF '} {name:20s} {os.path.basename(outs[build])}")
                if not same:
                    differ.append(f"{name} ({build})")
    print(f"{compared - len(differ)} identical, {len(differ)} differ" + (": " + ", ".join(differ) if differ else ""))
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
