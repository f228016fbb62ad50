#!/usr/bin/env python3
"""Label maps (issue 18): keymesh.contour_labels against VTK's
vtkDiscreteFlyingEdges3D over the same labels, in the same process.

    PYTHONPATH=build/python /usr/bin/python3 bench/labels_bench.py [--threads 2] [--repeat 5] [--json]

The whole AAL atlas (Debian mricron-data, 181x217x181 uint8, 116 labels), all
labels, no smoothing:
  - keymesh discrete-mc (network: each label's surface, points shared);
  - keymesh discrete-mc --per-label (each label's own surface, as VTK writes them);
  - keymesh surface nets (network: every interface once);
  - vtkDiscreteFlyingEdges3D with one contour value per label (the labels'
    surfaces with their own points, as --per-label), vtkSMPTools at --threads;
then the smoothing alone (contour_labels' own "smooth" stage, default 16
iterations) for both methods. Medians of --repeat runs after one warm-up,
the load average beside them. With --json, one JSON object per row.
"""
import argparse
import json
import os
import statistics
import sys
import time

import peer_common

AAL = "/usr/share/mricron/templates/aal.nii.gz"


def median_time(fn, repeat):
    fn()  # warm-up
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--input", default=AAL)
    a = ap.parse_args()
    if not os.path.exists(a.input):
        print(f"skipped: {a.input} not found (apt-get install mricron-data)")
        return 77
    import numpy as np
    import keymesh
    import vtk
    from vtk.util import numpy_support as ns

    volume = keymesh.read(a.input)
    array = volume.array  # axis 0 = x, a view of the samples
    labels = [int(v) for v in np.unique(array) if v != 0]
    reader = vtk.vtkNIFTIImageReader()
    reader.SetFileName(a.input)
    reader.Update()
    image = reader.GetOutput()
    assert ns.vtk_to_numpy(image.GetPointData().GetScalars()).size == array.size
    vtk.vtkSMPTools.Initialize(a.threads)

    rows = []

    def row(name, seconds, **extra):
        r = {"bench": "labels", "dataset": os.path.basename(a.input), "case": name, "threads": a.threads,
             "seconds": round(seconds, 4), "labels": len(labels), "loadavg": round(os.getloadavg()[0], 2)}
        r.update(extra)
        rows.append(r)

    def km(**kw):
        return keymesh.contour_labels(volume, smoothing=False, threads=a.threads, **kw)

    for name, kw in (("keymesh discrete-mc (network)", {"method": "discrete_marching_cubes"}),
                     ("keymesh discrete-mc --per-label", {"method": "discrete_marching_cubes", "per_label": True}),
                     ("keymesh surface nets (network)", {"method": "surface_nets"}),
                     ("keymesh surface nets --per-label", {"method": "surface_nets", "per_label": True})):
        mesh = km(**kw)
        row(name, median_time(lambda: km(**kw), a.repeat), points=mesh.n_points, triangles=mesh.n_cells)

    def vtk_fe():
        # scalars: the label of each surface (as keymesh's label field)
        fe = peer_common.contour_filter(vtk.vtkDiscreteFlyingEdges3D, image, labels, scalars=True)
        fe.Update()
        return fe.GetOutput()

    out = vtk_fe()
    row("vtkDiscreteFlyingEdges3D (all labels)", median_time(vtk_fe, a.repeat), points=out.GetNumberOfPoints(),
        triangles=out.GetNumberOfPolys())

    for name, method in (("smoothing, surface nets (16 constrained iterations)", "surface_nets"),
                         ("smoothing, discrete-mc (16 Taubin iterations)", "discrete_marching_cubes")):
        times = []
        for _ in range(a.repeat):
            keymesh.contour_labels(volume, method=method, threads=a.threads)
            times.append(keymesh._labels.last_labels_info["smooth"])
        row(name, statistics.median(times))

    if a.json:
        for r in rows:
            print(json.dumps(r))
        return 0
    fe = next(r for r in rows if r["case"].startswith("vtk"))["seconds"]
    print(f"AAL atlas, {len(labels)} labels, {a.threads} threads, medians of {a.repeat} "
          f"(load {rows[0]['loadavg']}):")
    print(f"| case | seconds | points | triangles | vs vtkDiscreteFlyingEdges3D |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for r in rows:
        ratio = f"{fe / r['seconds']:.1f}x faster" if not r["case"].startswith(("vtk", "smoothing")) else ""
        print(f"| {r['case']} | {r['seconds']:.3f} | {r.get('points', '')} | {r.get('triangles', '')} | {ratio} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
