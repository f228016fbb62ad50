"""Times VTK's decimation filters on a surface file for bench/run.py (the
paper's Table 5 peers): vtkBinnedDecimation and vtkQuadricClustering with a
bin size of one voxel (the grid keymesh's coarsening snaps to). JSON lines."""
import os
import sys

import vtk

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import peer_common  # noqa: E402


def main():
    a, surface = peer_common.surface_peer_args(vtk.vtkXMLPolyDataReader)
    bins = a.size - 1
    for name in ("vtkBinnedDecimation", "vtkQuadricClustering"):
        def make():
            f = getattr(vtk, name)()
            f.SetInputData(surface)
            f.SetNumberOfDivisions(bins, bins, bins)
            if name == "vtkBinnedDecimation":
                f.SetPointGenerationModeToBinAverages()
            return f

        times, counts = peer_common.time_updates(make, a.reps, lambda out: {"cells": out.GetNumberOfCells()})
        peer_common.print_row({"bench": "coarsen", "tool": name, "size": a.size, "threads": 1, **counts}, times)


if __name__ == "__main__":
    main()
