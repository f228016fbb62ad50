"""Times vtkLinearSubdivisionFilter (one level) on a surface file for
bench/run.py. Prints one JSON line. Only Update() is timed."""
import argparse
import json
import resource
import statistics
import time

import vtk


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--size", type=int, required=True)
    ap.add_argument("--reps", type=int, default=5)
    a = ap.parse_args()
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(a.mesh)
    r.Update()
    surface = r.GetOutput()
    times = []
    for _ in range(a.reps):
        f = vtk.vtkLinearSubdivisionFilter()
        f.SetInputData(surface)
        f.SetNumberOfSubdivisions(1)
        t0 = time.perf_counter()
        f.Update()
        times.append(time.perf_counter() - t0)
        points, cells = f.GetOutput().GetNumberOfPoints(), f.GetOutput().GetNumberOfCells()
        del f
    print(json.dumps({"bench": "subdivide", "tool": "vtkLinearSubdivisionFilter", "size": a.size, "threads": 1,
                      "points": points, "cells": cells, "median": statistics.median(times), "min": min(times),
                      "max": max(times), "first": times[0], "reps": a.reps,
                      "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}), flush=True)


if __name__ == "__main__":
    main()
