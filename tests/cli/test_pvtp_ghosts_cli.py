"""`mpirun -np P keymesh contour VOL -o OUT.pvtp`: pieces with VTK's ghost
marks (issue 33).

Without them ParaView's Feature Edges found boundary edges along the ranks'
shared planes (a seam of duplicated points) until Clean was applied. Each
piece now carries one layer of ghost cells (the neighbouring ranks'
triangles that use a point it holds) marked DUPLICATECELL in a vtkGhostType
cell array, and marks DUPLICATEPOINT on the points another rank owns.

Checked on a closed sphere (two nested isosurfaces) with -np 2 and 3:
- VTK's vtkXMLPPolyDataReader reads all pieces in one process and
  vtkFeatureEdges (boundary edges only) finds none. VTK >= 9.2 does that by
  itself (RemoveGhostInterfaces, on by default). VTK 9.1 drops ghost cells
  and then reports the edges between owned and ghost cells as boundaries
  (the regression that RemoveGhostInterfaces fixed, paraview#21454): there
  the marks are handed to the filter under another name, so that a ghost
  cell counts as the neighbour it is, and its output edges carry the mark of
  the cell they came from: none may come from an owned cell (the ghost
  layer's outer rim, which VTK >= 9.2 drops, comes from ghost cells only).
- The marks follow VTK's rule: every global point is unmarked in exactly one
  piece; the unmarked cells of all pieces are the gathered mesh's triangles,
  each once; every ghost cell is an unmarked cell of another piece and uses
  a point of its own piece.
- keymesh's own .pvtp reader drops the ghost cells: `check --expect-closed`
  passes and `convert` gives the gathered file's points and triangles.
Skipped (77) without mpirun, an MPI build of keymesh or VTK."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, mpirun, require_mpi, require_vtk, run, tempdir  # noqa: E402

require_vtk()

import numpy as np  # noqa: E402
import vtk  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

from kmtest import points_of, read_polydata, triangles_of  # noqa: E402

D = tempdir()
N = 40
SPHERE = os.path.join(D, "sphere.raw")
run("generate", "sphere", "--size", N, "-o", SPHERE, "-q")
ARGS = ["--dims", N, N, N, "--iso", 17.5, "--iso", 9.25, "-q"]

require_mpi("contour", SPHERE, *ARGS, "-o", os.path.join(D, "probe.ply"))

RANKS = (2, 3)
GATHERED = os.path.join(D, "gathered.ply")
run("contour", SPHERE, *ARGS, "-o", GATHERED)
for P in RANKS:
    mpirun(P, "contour", SPHERE, *ARGS, "-o", os.path.join(D, f"p{P}.pvtp"))


def sorted_rows(t):
    return t[np.lexsort(t.T[::-1])]


def boundary_edges(index):
    """Boundary edges vtkFeatureEdges finds on all pieces read in one
    process, ghost-aware: (edges, ghost cells read)."""
    reader = vtk.vtkXMLPPolyDataReader()
    reader.SetFileName(index)
    reader.Update()
    data = reader.GetOutput()
    marks = data.GetCellData().GetArray("vtkGhostType")
    ghost_cells = 0 if marks is None else int((ns.vtk_to_numpy(marks) & 1).sum())
    edges = vtk.vtkFeatureEdges()
    edges.BoundaryEdgesOn()
    edges.FeatureEdgesOff()
    edges.NonManifoldEdgesOff()
    edges.ManifoldEdgesOff()
    if hasattr(edges, "SetRemoveGhostInterfaces"):  # VTK >= 9.2
        edges.SetInputData(data)
        edges.RemoveGhostInterfacesOn()
        edges.Update()
        return edges.GetOutput().GetNumberOfCells(), ghost_cells
    # VTK 9.1: the marks under another name (ghost cells count as neighbours);
    # the edges from owned cells are the boundary edges.
    copy = vtk.vtkPolyData()
    copy.ShallowCopy(data)
    if marks is not None:
        renamed = vtk.vtkUnsignedCharArray()
        renamed.DeepCopy(marks)
        renamed.SetName("ghost_mark")
        copy.GetCellData().RemoveArray("vtkGhostType")
        copy.GetCellData().AddArray(renamed)
    edges.SetInputData(copy)
    edges.Update()
    out = edges.GetOutput()
    mark = out.GetCellData().GetArray("ghost_mark")
    if mark is None:
        return out.GetNumberOfCells(), ghost_cells
    return int(((ns.vtk_to_numpy(mark) & 1) == 0).sum()), ghost_cells


def feature_edges_find_no_boundary():
    for P in RANKS:
        found, ghosts = boundary_edges(os.path.join(D, f"p{P}.pvtp"))
        assert found == 0, f"-np {P}: vtkFeatureEdges finds {found} boundary edges ({ghosts} ghost cells read)"
        print(f"        -np {P}: no boundary edge, {ghosts} ghost cells")


def marks_follow_vtk_rules():
    ref = read_polydata(GATHERED)
    ref_tris = triangles_of(ref)
    for P in RANKS:
        owners = np.zeros(ref.GetNumberOfPoints(), dtype=np.int64)
        owned, ghost = [], []
        for q in range(P):
            piece = read_polydata(os.path.join(D, f"p{P}_{q}.vtp"))
            gid = ns.vtk_to_numpy(piece.GetPointData().GetArray("GlobalPointIds")).astype(np.int64)
            pmark = ns.vtk_to_numpy(piece.GetPointData().GetArray("vtkGhostType"))
            cmark = ns.vtk_to_numpy(piece.GetCellData().GetArray("vtkGhostType"))
            assert set(np.unique(pmark)) <= {0, 1} and set(np.unique(cmark)) <= {0, 1}
            np.add.at(owners, gid[pmark == 0], 1)
            t = triangles_of(piece)
            assert len(t) == len(cmark)
            owned.append(gid[t[cmark == 0]])
            ghost.append(gid[t[cmark == 1]])
            # A ghost cell uses a point of the piece's own cells.
            own_points = np.unique(t[cmark == 0])
            assert np.isin(t[cmark == 1], own_points).any(axis=1).all(), f"-np {P} piece {q}: stray ghost cell"
        assert (owners == 1).all(), f"-np {P}: points unmarked in {sorted(set(owners.tolist()))} pieces"
        allowned = np.concatenate(owned)
        assert np.array_equal(sorted_rows(allowned), sorted_rows(ref_tris)), f"-np {P}: owned cells != gathered"
        assert sum(len(g) for g in ghost) > 0, f"-np {P}: no ghost cell"
        for q in range(P):
            others = {tuple(r) for k, o in enumerate(owned) if k != q for r in o.tolist()}
            assert all(tuple(r) in others for r in ghost[q].tolist()), \
                f"-np {P} piece {q}: a ghost cell no other piece owns"


def keymesh_reader_drops_ghost_cells():
    ref = read_polydata(GATHERED)
    ref_pts, ref_tris = points_of(ref), triangles_of(ref)
    for P in RANKS:
        index = os.path.join(D, f"p{P}.pvtp")
        run("check", index, "--expect-closed", "-q")
        out = os.path.join(D, f"p{P}_read.ply")
        run("convert", index, "-o", out, "-q")
        got = read_polydata(out)
        assert np.array_equal(points_of(got), ref_pts), f"-np {P}: points differ from the gathered file"
        tris = triangles_of(got)
        assert len(tris) == len(ref_tris), f"-np {P}: {len(tris)} triangles for {len(ref_tris)}"
        assert np.array_equal(sorted_rows(tris), sorted_rows(ref_tris)), f"-np {P}: triangles differ"


check("VTK's parallel reader + Feature Edges: no boundary edge on the closed sphere", feature_edges_find_no_boundary)
check("vtkGhostType marks follow VTK's rules", marks_follow_vtk_rules)
check("keymesh's .pvtp reader drops ghost cells: the gathered mesh", keymesh_reader_drops_ghost_cells)
finish()
