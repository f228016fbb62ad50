"""Times VTK's contour filters on the Spherical Distance field (or a volume
file) for bench/run.py. Prints one JSON line per filter.

Run with Debian's /usr/bin/python3 (python3-vtk9). Only Update() is timed;
the volume is built once. VTK's SMP backend (TBB in Debian) uses --threads.
"""
import argparse
import json
import resource
import os
import statistics
import sys
import time

import numpy as np
import vtk
from vtk.util import numpy_support as ns

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import datasets  # noqa: E402


def clean(img, a):
    """vtkCleanPolyData on the soup of the contour: every triangle with its
    own three points (what marching cubes writes before welding); only the
    weld is timed."""
    fe = vtk.vtkFlyingEdges3D()
    fe.SetInputData(img)
    fe.SetValue(0, a.iso)
    fe.ComputeNormalsOff()
    fe.ComputeScalarsOff()
    fe.Update()
    mesh = fe.GetOutput()
    pts = ns.vtk_to_numpy(mesh.GetPoints().GetData())
    conn = ns.vtk_to_numpy(mesh.GetPolys().GetConnectivityArray())
    soup = vtk.vtkPolyData()
    p = vtk.vtkPoints()
    p.SetData(ns.numpy_to_vtk(np.ascontiguousarray(pts[conn]), deep=True))
    soup.SetPoints(p)
    cells = vtk.vtkCellArray()
    cells.SetData(ns.numpy_to_vtk(np.arange(0, len(conn) + 1, 3, dtype=np.int64), deep=True),
                  ns.numpy_to_vtk(np.arange(len(conn), dtype=np.int64), deep=True))
    soup.SetPolys(cells)
    del fe, mesh
    times = []
    for _ in range(a.reps):
        f = vtk.vtkCleanPolyData()
        f.SetInputData(soup)
        f.SetTolerance(0.0)
        f.PointMergingOn()
        t0 = time.perf_counter()
        f.Update()
        times.append(time.perf_counter() - t0)
        points, ncells = f.GetOutput().GetNumberOfPoints(), f.GetOutput().GetNumberOfCells()
        del f
    print(json.dumps({"bench": "contour", "tool": "vtkCleanPolyData", "size": a.size, "iso": a.iso, "threads": 1,
                      "soup_points": len(conn), "points": points, "cells": ncells,
                      "median": statistics.median(times), "min": min(times), "max": max(times), "first": times[0],
                      "reps": a.reps, "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}),
          flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, required=True)
    ap.add_argument("--file", help="read this .vti (vtkXMLImageDataReader) instead of building the field in memory")
    ap.add_argument("--iso", type=float, required=True)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--filters", default="vtkFlyingEdges3D,vtkMarchingCubes",
                    help="comma-separated; vtkCleanPolyData welds the triangle soup of the contour by "
                         "coordinates (VTK's VERTEX-WELD: tolerance 0, point merging on)")
    a = ap.parse_args()
    vtk.vtkSMPTools.Initialize(a.threads)
    if a.file:
        reader = vtk.vtkXMLImageDataReader()
        reader.SetFileName(a.file)
        reader.Update()
        img = reader.GetOutput()
    else:
        d = datasets.sphere(a.size)
        img = vtk.vtkImageData()
        img.SetDimensions(a.size, a.size, a.size)
        arr = ns.numpy_to_vtk(d.ravel(), deep=True)
        arr.SetName("distance")
        img.GetPointData().SetScalars(arr)
        del d
    for name in a.filters.split(","):
        if name == "vtkCleanPolyData":
            clean(img, a)
            continue
        times = []
        points = cells = 0
        for _ in range(a.reps):
            f = getattr(vtk, name)()
            f.SetInputData(img)
            f.SetValue(0, a.iso)
            f.ComputeNormalsOff()
            f.ComputeScalarsOff()
            if hasattr(f, "ComputeGradientsOff"):
                f.ComputeGradientsOff()
            t0 = time.perf_counter()
            f.Update()
            times.append(time.perf_counter() - t0)
            points, cells = f.GetOutput().GetNumberOfPoints(), f.GetOutput().GetNumberOfCells()
            del f
        print(json.dumps({"bench": "contour", "tool": name, "size": a.size, "iso": a.iso,
                          "threads": a.threads if name == "vtkFlyingEdges3D" else 1,
                          "points": points, "cells": cells, "median": statistics.median(times),
                          "min": min(times), "max": max(times), "first": times[0], "reps": a.reps,
                          "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}), flush=True)


if __name__ == "__main__":
    main()
