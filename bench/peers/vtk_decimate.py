"""Times VTK's decimation filters on a surface file for bench/run.py (the
paper's Table 5 peers): vtkBinnedDecimation and vtkQuadricClustering with a
bin size of one voxel (the grid keymesh's coarsening snaps to). JSON lines."""
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
    bins = a.size - 1
    for name in ("vtkBinnedDecimation", "vtkQuadricClustering"):
        times = []
        for _ in range(a.reps):
            f = getattr(vtk, name)()
            f.SetInputData(surface)
            f.SetNumberOfDivisions(bins, bins, bins)
            if name == "vtkBinnedDecimation":
                f.SetPointGenerationModeToBinAverages()
            t0 = time.perf_counter()
            f.Update()
            times.append(time.perf_counter() - t0)
            cells = f.GetOutput().GetNumberOfCells()
            del f
        print(json.dumps({"bench": "coarsen", "tool": name, "size": a.size, "threads": 1, "cells": cells,
                          "median": statistics.median(times), "min": min(times), "max": max(times),
                          "first": times[0], "reps": a.reps,
                          "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}), flush=True)


if __name__ == "__main__":
    main()
