"""Times vtkContour3DLinearGrid (points merged) on a tetrahedral .vtu for
bench/run.py, and how long VTK takes to build the same kind of grid with its
own vtkDataSetTriangleFilter from the volume (optional). Prints JSON lines.

Run with Debian's /usr/bin/python3 (python3-vtk9). Only Update() is timed.
"""
import argparse
import json
import resource
import statistics
import time

import vtk


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vtu", required=True)
    ap.add_argument("--size", type=int, required=True)
    ap.add_argument("--iso", type=float, required=True)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reps", type=int, default=5)
    a = ap.parse_args()
    vtk.vtkSMPTools.Initialize(a.threads)
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(a.vtu)
    r.Update()
    ug = r.GetOutput()
    ug.GetPointData().SetActiveScalars(ug.GetPointData().GetArrayName(0))
    times = []
    points = cells = 0
    for _ in range(a.reps):
        f = vtk.vtkContour3DLinearGrid()
        f.SetInputData(ug)
        f.SetValue(0, a.iso)
        f.MergePointsOn()
        f.InterpolateAttributesOff()
        f.ComputeNormalsOff()
        t0 = time.perf_counter()
        f.Update()
        times.append(time.perf_counter() - t0)
        points, cells = f.GetOutput().GetNumberOfPoints(), f.GetOutput().GetNumberOfCells()
        del f
    print(json.dumps({"bench": "contour", "grid": "tet5", "tool": "vtkContour3DLinearGrid", "size": a.size,
                      "iso": a.iso, "threads": a.threads, "points": points, "cells": cells,
                      "median": statistics.median(times), "min": min(times), "max": max(times), "first": times[0],
                      "reps": a.reps, "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}),
          flush=True)


if __name__ == "__main__":
    main()
