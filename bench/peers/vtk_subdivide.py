"""Times vtkLinearSubdivisionFilter (one level) on a surface file for
bench/run.py. Prints one JSON line. Only Update() is timed."""
import os
import sys

import vtk

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import peer_common  # noqa: E402


def main():
    a, surface = peer_common.surface_peer_args(vtk.vtkXMLPolyDataReader)

    def make():
        f = vtk.vtkLinearSubdivisionFilter()
        f.SetInputData(surface)
        f.SetNumberOfSubdivisions(1)
        return f

    times, counts = peer_common.time_updates(make, a.reps, peer_common.points_and_cells)
    peer_common.print_row({"bench": "subdivide", "tool": "vtkLinearSubdivisionFilter", "size": a.size,
                           "threads": 1, **counts}, times)


if __name__ == "__main__":
    main()
