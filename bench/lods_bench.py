#!/usr/bin/env python3
"""Multi-resolution label meshes (issue 37): `keymesh labels --format
precomputed` against VTK's pipeline for the same job, on this machine.

    /usr/bin/python3 bench/lods_bench.py --keymesh build/keymesh [--threads 2] [--repeat 5] [--json]

keymesh: a fresh CLI process per run (as a task queue calls it), the AAL atlas
(Debian mricron-data, 181 x 217 x 181 uint8, 116 labels), surface nets with
the default 16 smoothing steps, 32^3 chunks, Draco fragments; --lods 1 (level
0 only) and --lods 3, so the cost of the coarser levels is the difference;
and --smooth 0. Seconds are the report's stages (labels: meshing, cutting,
levels; write: Draco, manifests, chunk store) and the process's wall time.

VTK (in this process, vtkSMPTools at --threads): vtkDiscreteFlyingEdges3D over
every label (level 0), then vtkQuadricDecimation of that mesh to keymesh's
triangle count at each coarser level (equal triangle counts), no smoothing,
no file written: the peer's cost is a lower bound of the same job.
Medians of --repeat rounds (one run of each keymesh case per round, so drift
falls on every case alike) after one warm-up; the load average beside them.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

AAL = "/usr/share/mricron/templates/aal.nii.gz"


def keymesh_run(keymesh, src, out, threads, extra):
    rep = out + ".json"
    shutil.rmtree(out, ignore_errors=True)
    cmd = [keymesh, "labels", src, "-o", out, "--format", "precomputed", "--chunk-shape", "32", "32", "32",
           "--threads", str(threads), "-q", "--report", rep, *extra]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdin=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    r = json.load(open(rep))
    return {"wall": wall, "labels": r["seconds"]["labels"], "write": r["seconds"]["write"],
            "triangles_per_lod": r.get("triangles_per_lod", []), "segments": r["segments"],
            "peak_rss_mib": r.get("peak_rss_mib", 0)}


def median_of(runs, key):
    return statistics.median(r[key] for r in runs)


def vtk_rows(src, threads, repeat, targets, voxels):
    import numpy as np
    import vtk
    from vtk.util import numpy_support as ns
    reader = vtk.vtkNIFTIImageReader()
    reader.SetFileName(src)
    reader.Update()
    image = reader.GetOutput()
    labels = [int(v) for v in np.unique(ns.vtk_to_numpy(image.GetPointData().GetScalars())) if v != 0]
    vtk.vtkSMPTools.Initialize(threads)

    def fe():
        f = vtk.vtkDiscreteFlyingEdges3D()
        f.SetInputData(image)
        f.ComputeScalarsOff()
        f.ComputeNormalsOff()
        f.ComputeGradientsOff()
        for i, v in enumerate(labels):
            f.SetValue(i, v)
        f.Update()
        return f.GetOutput()

    def timed(fn):
        fn()
        times = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t0)
        return statistics.median(times), out

    t_fe, fine = timed(fe)
    rows = [{"case": "vtkDiscreteFlyingEdges3D (level 0)", "seconds": t_fe, "triangles": [fine.GetNumberOfPolys()]}]
    for level, target in enumerate(targets[1:], start=1):
        def decimate():
            d = vtk.vtkQuadricDecimation()
            d.SetInputData(fine)
            d.SetTargetReduction(max(0.0, 1.0 - target / fine.GetNumberOfPolys()))
            d.Update()
            return d.GetOutput()
        t, out = timed(decimate)
        rows.append({"case": f"vtkQuadricDecimation to level {level}'s count", "seconds": t,
                     "triangles": [out.GetNumberOfPolys()]})
    for r in rows:
        r["mvox_per_s"] = voxels / r["seconds"] / 1e6
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--keymesh", default=os.path.join(os.path.dirname(__file__), "..", "build", "keymesh"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--input", default=AAL)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    if not os.path.exists(a.input):
        print(f"skipped: {a.input} not found (apt-get install mricron-data)")
        return 77
    voxels = 181 * 217 * 181 if a.input == AAL else None
    if voxels is None:
        raise SystemExit("lods_bench: only the AAL atlas' size is known here")
    rows = []
    load = round(os.getloadavg()[0], 2)
    with tempfile.TemporaryDirectory(prefix="keymesh-lods-") as work:
        out = os.path.join(work, "ng")
        cases = (("keymesh --lods 1 (level 0 only)", ["--lods", "1"]),
                 ("keymesh --lods 3", ["--lods", "3"]),
                 ("keymesh --lods 3 --smooth 0", ["--lods", "3", "--smooth", "0"]))
        for _, extra in cases:  # warm-up
            keymesh_run(a.keymesh, a.input, out, a.threads, extra)
        # Rounds of one run per case, so that the machine's drift (other
        # tenants of a shared VM) falls on every case alike; each round's
        # (--lods 3 - --lods 1) / 2 / --lods 1 is a per-level ratio from runs
        # seconds apart.
        runs = {name: [] for name, _ in cases}
        for _ in range(a.repeat):
            for name, extra in cases:
                runs[name].append(keymesh_run(a.keymesh, a.input, out, a.threads, extra))
        for name, _ in cases:
            rs = runs[name]
            rows.append({"case": name, "seconds": median_of(rs, "wall"), "labels_stage": median_of(rs, "labels"),
                         "write_stage": median_of(rs, "write"), "triangles": rs[0]["triangles_per_lod"],
                         "peak_rss_mib": rs[0]["peak_rss_mib"], "mvox_per_s": voxels / median_of(rs, "wall") / 1e6})
        level0, all3 = runs[cases[0][0]], runs[cases[1][0]]
        ratios = sorted((b["wall"] - a0["wall"]) / 2 / a0["wall"] for a0, b in zip(level0, all3))
        rows[1]["per_level_ratio_median"] = statistics.median(ratios)
        rows[1]["per_level_ratio_range"] = [ratios[0], ratios[-1]]
    targets = rows[1]["triangles"]
    rows += vtk_rows(a.input, a.threads, a.repeat, targets, voxels)
    for r in rows:
        r.update({"bench": "lods", "dataset": os.path.basename(a.input), "threads": a.threads, "loadavg": load})
    if a.json:
        for r in rows:
            print(json.dumps(r))
        return 0
    l1, l3 = rows[0], rows[1]
    print(f"AAL atlas (7.1 Mvox, 116 labels), {a.threads} threads, medians of {a.repeat}, load {load}, "
          f"{time.strftime('%Y-%m-%d')}:")
    print("| case | seconds | Mvox/s | triangles per level | labels stage s | write stage s |")
    print("| --- | ---: | ---: | --- | ---: | ---: |")
    for r in rows:
        print(f"| {r['case']} | {r['seconds']:.3f} | {r['mvox_per_s']:.1f} | {r['triangles']} | "
              f"{r.get('labels_stage', float('nan')):.3f} | {r.get('write_stage', float('nan')):.3f} |")
    extra = (l3["seconds"] - l1["seconds"]) / 2
    lo, hi = l3["per_level_ratio_range"]
    print(f"each coarser level: {extra:.3f} s = {100 * extra / l1['seconds']:.1f} % of level 0's run (medians); "
          f"per round: median {100 * l3['per_level_ratio_median']:.1f} %, {100 * lo:.1f}-{100 * hi:.1f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
