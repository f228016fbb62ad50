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


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, required=True)
    ap.add_argument("--file", help="read this .vti (vtkXMLImageDataReader) instead of building the field in memory")
    ap.add_argument("--iso", type=float, required=True)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--filters", default="vtkFlyingEdges3D,vtkMarchingCubes")
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
