"""Peers for bench/run.py that contour a numpy volume: scikit-image's
marching_cubes (method="lorensen", single-threaded; it also computes normals
and values, which cannot be turned off) and OpenVDB's volumeToMesh through
pyopenvdb's FloatGrid.convertToPolygons (adaptivity 0; TBB, all cores; its
mesher is dual: one point per cut voxel, quads and triangles). One JSON line.

Run with Debian's /usr/bin/python3. Only the contour call is timed; building
the volume (and OpenVDB's sparse grid from it) is not.
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import datasets  # noqa: E402
import peer_common  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tool", choices=("skimage", "openvdb"), required=True)
    ap.add_argument("--size", type=int, required=True)
    ap.add_argument("--file", help="a .nrrd written by bench/datasets.py instead of the sphere")
    ap.add_argument("--iso", type=float, required=True)
    ap.add_argument("--reps", type=int, default=5)
    a = ap.parse_args()
    vol = np.array(datasets.read_nrrd(a.file)) if a.file else datasets.sphere(a.size)  # writable (skimage)
    times = []
    if a.tool == "skimage":
        from skimage import measure
        import skimage
        version, threads = skimage.__version__, 1
        for _ in range(a.reps):
            t0 = time.perf_counter()
            verts, faces, _, _ = measure.marching_cubes(vol, level=a.iso, method="lorensen")
            times.append(time.perf_counter() - t0)
            points, cells = len(verts), len(faces)
            del verts, faces
        name = "skimage-marching_cubes"
    else:
        import pyopenvdb as vdb
        version, threads = ".".join(map(str, getattr(vdb, "LIBRARY_VERSION", ()))), os.cpu_count()
        # background: a value on the side of the isovalue that the array's
        # border is on, so the sparse grid's outside adds no surface
        grid = vdb.FloatGrid(background=float(vol.max()) if not a.file else 0.0)
        grid.copyFromArray(vol)
        del vol
        for _ in range(a.reps):
            t0 = time.perf_counter()
            pts, tris, quads = grid.convertToPolygons(isovalue=a.iso, adaptivity=0.0)
            times.append(time.perf_counter() - t0)
            points, cells = len(pts), len(tris) + 2 * len(quads)
            del pts, tris, quads
        name = "openvdb-volumeToMesh"
    peer_common.print_row({"bench": "contour", "tool": name, "version": str(version), "size": a.size, "iso": a.iso,
                           "threads": threads, "points": points, "cells": cells, "cells_note":
                           "triangles + 2 x quads" if a.tool == "openvdb" else "triangles"}, times)


if __name__ == "__main__":
    main()
