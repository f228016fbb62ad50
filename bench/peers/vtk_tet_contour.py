"""Times vtkContour3DLinearGrid (points merged) on a tetrahedral .vtu for
bench/run.py, and how long VTK takes to build the same kind of grid with its
own vtkDataSetTriangleFilter from the volume (optional). Prints JSON lines.

Run with Debian's /usr/bin/python3 (python3-vtk9). Only Update() is timed.
"""
import argparse
import os
import sys

import vtk

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import peer_common  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vtu", required=True)
    ap.add_argument("--size", type=int, required=True)
    ap.add_argument("--iso", type=float, required=True)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reps", type=int, default=5)
    a = ap.parse_args()
    vtk.vtkSMPTools.Initialize(a.threads)
    ug = peer_common.read(vtk.vtkXMLUnstructuredGridReader, a.vtu)
    ug.GetPointData().SetActiveScalars(ug.GetPointData().GetArrayName(0))

    def make():
        f = peer_common.contour_filter(vtk.vtkContour3DLinearGrid, ug, [a.iso])
        f.MergePointsOn()
        f.InterpolateAttributesOff()
        return f

    times, counts = peer_common.time_updates(make, a.reps, peer_common.points_and_cells)
    peer_common.print_row({"bench": "contour", "grid": "tet5", "tool": "vtkContour3DLinearGrid", "size": a.size,
                           "iso": a.iso, "threads": a.threads, **counts}, times)

if __name__ == "__main__":
    main()
