#!/usr/bin/env python3
"""keymesh.contour from Python vs the CLI's seconds.contour vs scikit-image.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_bench.py --keymesh build/keymesh [--size 512]

Contours the paper's Spherical Distance field (distance of every sample from
grid point (N/2, N/2, N/2)) at iso N/2 - 0.999 as a float32 numpy array
(C order), as a keymesh.Volume (read in place), with `keymesh contour`
(seconds.contour of its --report: classification + generation + KEY-REDUCE,
the same work) and with skimage.measure.marching_cubes. Medians of --repeat
runs (skimage: one run). Like the CLI, the script re-executes itself once
with GLIBC_TUNABLES=glibc.malloc.hugetlb=1 (2 MiB pages for large arrays)
unless --no-huge-pages.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

TUNABLE = "glibc.malloc.hugetlb=1"


def reexec_with_huge_pages(args):
    tunables = os.environ.get("GLIBC_TUNABLES", "")
    if args.no_huge_pages or TUNABLE in tunables or os.environ.get("KEYMESH_HUGE_PAGES") == "0":
        return
    env = dict(os.environ, GLIBC_TUNABLES=(tunables + ":" if tunables else "") + TUNABLE)
    os.execve(sys.executable, [sys.executable] + sys.argv, env)


def median_time(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--keymesh", default="build/keymesh", help="the CLI")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--normals", default="none", help="none (the CLI's default) or average")
    ap.add_argument("--no-skimage", action="store_true")
    ap.add_argument("--no-huge-pages", action="store_true")
    args = ap.parse_args()
    reexec_with_huge_pages(args)

    import numpy as np
    import keymesh

    n = args.size
    iso = n / 2 - 0.999
    c = np.float32(n // 2)
    ax = np.arange(n, dtype=np.float32) - c
    vol = np.sqrt(ax[:, None, None] ** 2 + ax[None, :, None] ** 2 + ax[None, None, :] ** 2)
    print(f"{n}^3 float32 sphere, iso {iso}, normals={args.normals}, threads={args.threads or 'all'}, "
          f"huge pages: {TUNABLE in os.environ.get('GLIBC_TUNABLES', '')}")

    def run_array():
        return keymesh.contour(vol, iso, normals=args.normals, threads=args.threads)

    mesh = run_array()
    print(f"  {mesh.n_points} points, {mesh.n_cells} triangles")
    py_med, py_min = median_time(run_array, args.repeat)
    infos = []
    for _ in range(args.repeat):
        run_array()
        infos.append(dict(keymesh.last_contour_info))
    lib_med = statistics.median(i["contour"] for i in infos)
    copy_med = statistics.median(i["copy"] for i in infos)
    mirror_med = statistics.median(i["mirror"] for i in infos)

    volume = keymesh.Volume(vol)
    v_med, v_min = median_time(lambda: keymesh.contour(volume, iso, normals=args.normals, threads=args.threads),
                               args.repeat)

    cli = []
    with tempfile.TemporaryDirectory() as tmp:
        vti = os.path.join(tmp, "s.vti")
        subprocess.run([args.keymesh, "generate", "sphere", "--size", str(n), "-o", vti, "-q"], check=True)
        for _ in range(args.repeat):
            report = os.path.join(tmp, "r.json")
            cmd = [args.keymesh, "contour", vti, "-o", os.path.join(tmp, "o.ply"), "--iso", str(iso), "-q",
                   "--normals", args.normals, "--report", report]
            if args.threads:
                cmd += ["--threads", str(args.threads)]
            subprocess.run(cmd, check=True)
            with open(report) as f:
                r = json.load(f)
            assert r["points"] == mesh.n_points and r["cells"] == mesh.n_cells
            cli.append(r["seconds"]["contour"])
    cli_med = statistics.median(cli)

    print(f"  keymesh.contour(numpy C-order array): {py_med:.3f} s median, {py_min:.3f} min "
          f"(copy {copy_med:.3f} + library {lib_med:.3f} + mirror {mirror_med:.3f})")
    print(f"  keymesh.contour(keymesh.Volume), no copy: {v_med:.3f} s median, {v_min:.3f} min")
    print(f"  keymesh contour (CLI) seconds.contour: {cli_med:.3f} s median, {min(cli):.3f} min")
    print(f"  Python array / CLI: {py_med / cli_med:.3f}; Python Volume / CLI: {v_med / cli_med:.3f}")
    if not args.no_skimage:
        from skimage import measure

        t0 = time.perf_counter()
        verts, faces, _, _ = measure.marching_cubes(vol, iso)
        sk = time.perf_counter() - t0
        print(f"  skimage.measure.marching_cubes: {sk:.3f} s ({len(verts)} points, {len(faces)} triangles), "
              f"{sk / py_med:.1f}x keymesh.contour(array)")


if __name__ == "__main__":
    main()
