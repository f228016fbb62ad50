"""Times VTK's contour filters on the Spherical Distance field (or a volume
file) for bench/run.py. Prints one JSON line per filter.

Run with Debian's /usr/bin/python3 (python3-vtk9). Only Update() is timed;
the volume is built once. VTK's SMP backend (TBB in Debian) uses --threads.
"""
import argparse
import os
import sys

import numpy as np
import vtk
from vtk.util import numpy_support as ns

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import datasets  # noqa: E402
import peer_common  # noqa: E402


def clean(img, a):
    """vtkCleanPolyData on the soup of the contour: every triangle with its
    own three points (what marching cubes writes before welding); only the
    weld is timed."""
    fe = peer_common.contour_filter(vtk.vtkFlyingEdges3D, img, [a.iso])
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

    def make():
        f = vtk.vtkCleanPolyData()
        f.SetInputData(soup)
        f.SetTolerance(0.0)
        f.PointMergingOn()
        return f

    times, counts = peer_common.time_updates(make, a.reps, peer_common.points_and_cells)
    peer_common.print_row({"bench": "contour", "tool": "vtkCleanPolyData", "size": a.size, "iso": a.iso,
                           "threads": 1, "soup_points": len(conn), **counts}, times)


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
        img = peer_common.read(vtk.vtkXMLImageDataReader, a.file)
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
        times, counts = peer_common.time_updates(lambda: peer_common.contour_filter(getattr(vtk, name), img, [a.iso]),
                                                 a.reps, peer_common.points_and_cells)
        peer_common.print_row({"bench": "contour", "tool": name, "size": a.size, "iso": a.iso,
                               "threads": a.threads if name == "vtkFlyingEdges3D" else 1, **counts}, times)


if __name__ == "__main__":
    main()
