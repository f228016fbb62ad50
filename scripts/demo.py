#!/usr/bin/env python3
"""`make demo`: the main job on the built-in data.

1. generates the paper's 256^3 Spherical Distance field,
2. contours it at a closed isovalue with averaged normals (KEY-REDUCE weld),
3. checks that the result is a closed 2-manifold,
4. contours the MRI head from Debian's libvolpack1-dev (brainsmall.den),
5. writes both as .vtp and .ply under out/ and prints a short summary,
6. when mpirun is installed, contours the sphere again on 2 MPI ranks into a
   ParaView .pvtp of two pieces and gathered into one file, and compares the
   counts with step 2's.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

DEN = "/usr/share/doc/libvolpack1-dev/examples/brainsmall.den"


def keymesh(binary, *args):
    cmd = [binary, *map(str, args)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.stderr.write(p.stderr)
        sys.exit(f"demo: `{' '.join(cmd)}` failed with exit code {p.returncode}")
    return p


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--keymesh", default="build/keymesh", help="the command to run (default: build/keymesh)")
    ap.add_argument("--out", default="out", help="folder of the outputs (default: out)")
    ap.add_argument("--size", type=int, default=256, help="points along each axis of the sphere (default: 256)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    out = lambda name: os.path.join(a.out, name)  # noqa: E731
    n = a.size
    iso = n / 2 - 1.5
    rows = []

    keymesh(a.keymesh, "generate", "sphere", "--size", n, "-o", out(f"sphere{n}.vti"), "--quiet")
    for ext in ("vtp", "ply"):
        keymesh(a.keymesh, "contour", out(f"sphere{n}.vti"), "-o", out(f"sphere{n}.{ext}"), "--iso", iso,
                "--normals", "average", "--report", out(f"sphere{n}.{ext}.json"), "--quiet")
    keymesh(a.keymesh, "check", out(f"sphere{n}.vtp"), "--expect-closed", "--report", out(f"sphere{n}.check.json"))
    r = json.load(open(out(f"sphere{n}.vtp.json")))
    c = json.load(open(out(f"sphere{n}.check.json")))
    rows.append((f"sphere {n}^3, iso {iso}", r, f"closed 2-manifold: {'yes' if c['closed_manifold'] else 'no'}, "
                 f"Euler characteristic {c['euler_characteristic']}"))

    if os.path.exists(DEN):
        head_iso = 90.5
        for ext in ("vtp", "ply"):
            keymesh(a.keymesh, "contour", DEN, "-o", out(f"brainsmall.{ext}"), "--iso", head_iso,
                    "--normals", "average", "--report", out(f"brainsmall.{ext}.json"), "--quiet")
        keymesh(a.keymesh, "check", out("brainsmall.vtp"), "--report", out("brainsmall.check.json"))
        r = json.load(open(out("brainsmall.vtp.json")))
        c = json.load(open(out("brainsmall.check.json")))
        rows.append((f"MRI head (brainsmall.den {r['dims'][0]}x{r['dims'][1]}x{r['dims'][2]}), iso {head_iso}", r,
                     f"{c['components']} components, {c['boundary_edges']} boundary edges"))
    else:
        print(f"demo: {DEN} not found (Debian package libvolpack1-dev); MRI head skipped")

    mpi_line = None
    mpirun = shutil.which("mpirun")
    if mpirun:
        # The sphere's volume as NRRD (uncompressed): every rank reads only its slab of it.
        keymesh(a.keymesh, "generate", "sphere", "--size", n, "-o", out(f"sphere{n}.nrrd"), "--quiet")
        launch = [mpirun, "--oversubscribe", "-np", "2"] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])
        env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_MCA_btl_vader_single_copy_mechanism="none")
        ok = True
        for target in (out(f"sphere{n}_mpi.pvtp"), out(f"sphere{n}_mpi.vtp")):
            p = subprocess.run(launch + [a.keymesh, "contour", out(f"sphere{n}.nrrd"), "-o", target, "--iso", str(iso),
                                         "--normals", "average", "--quiet", "--report", target + ".json"],
                               capture_output=True, text=True, env=env, stdin=subprocess.DEVNULL, timeout=300)
            ok = ok and p.returncode == 0
        if ok:
            m = json.load(open(out(f"sphere{n}_mpi.pvtp.json")))
            pieces = ", ".join(f"{int(s['triangles']):,}" for s in m["distributed"]["per_rank"])
            ref, got = json.load(open(out(f"sphere{n}.vtp.json"))), json.load(open(out(f"sphere{n}_mpi.vtp.json")))
            same = ref["points"] == got["points"] and ref["cells"] == got["cells"]
            mpi_line = (f"  MPI, 2 ranks: sphere{n}_mpi.pvtp (pieces of {pieces} triangles, shared points named by "
                        f"GlobalPointIds), gathered sphere{n}_mpi.vtp: {got['points']:,} points, "
                        f"{got['cells']:,} triangles{' (the counts of one process)' if same else ' (DIFFERS from one process)'}")
        else:
            mpi_line = f"  MPI: mpirun could not run keymesh here (exit {p.returncode}); skipped"

    print(f"keymesh demo: outputs in {a.out}/")
    for title, r, topo in rows:
        s = r["seconds"]
        print(f"  {title}: {r['points']:,} points, {r['cells']:,} triangles, {topo}")
        print(f"    contour + weld + averaged normals {s['contour'] * 1000:.1f} ms on {r['threads']} threads "
              f"(read {s['read'] * 1000:.1f} ms, write {s['write'] * 1000:.1f} ms)")
    if mpi_line:
        print(mpi_line)
    print("  open the .vtp and .pvtp files in ParaView, the .ply files in MeshLab or Blender")


if __name__ == "__main__":
    main()
