"""Cross-check of `keymesh subdivide` against VTK (python3-vtk9):

- linear subdivision of contours of real volumes: the same points as
  vtkLinearSubdivisionFilter's, as sets within 1e-5, V' = V + E, F' = 4F;
- Bezier on the closed sphere contour: smaller deviation from the true
  sphere than linear, still a closed 2-manifold, normals and scalars carried;
- tet grids 1 -> 8 and scheme 24: counts, positive volumes summing to the
  box, and marching tets on the scheme-24 grid gives a closed sphere."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (check, finish, points_of, read_polydata, report, require_vtk, run, tempdir,  # noqa
                    triangles_of)

require_vtk()
import numpy as np  # noqa: E402
import vtk  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

D = tempdir()
DEN = "/usr/share/doc/libvolpack1-dev/examples/brainsmall.den"


def linear_vs_vtk(volume, iso, name):
    def t():
        src, out = os.path.join(D, f"{name}.vtp"), os.path.join(D, f"{name}-sub.vtp")
        run("contour", volume, "-o", src, "--iso", iso, "-q")
        run("subdivide", src, "-o", out, "-q", "--report", out + ".json")
        a = read_polydata(src)
        f = vtk.vtkLinearSubdivisionFilter()
        f.SetInputData(a)
        f.SetNumberOfSubdivisions(1)
        f.Update()
        ref = f.GetOutput()
        km = read_polydata(out)
        tris = triangles_of(a)
        edges = np.unique(np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1), axis=0)
        assert km.GetNumberOfPoints() == a.GetNumberOfPoints() + len(edges)
        assert km.GetNumberOfCells() == 4 * a.GetNumberOfCells()
        assert km.GetNumberOfPoints() == ref.GetNumberOfPoints(), (km.GetNumberOfPoints(), ref.GetNumberOfPoints())
        assert km.GetNumberOfCells() == ref.GetNumberOfCells()
        p, q = points_of(km), points_of(ref)
        p = p[np.lexsort((p[:, 2], p[:, 1], p[:, 0]))]
        q = q[np.lexsort((q[:, 2], q[:, 1], q[:, 0]))]
        assert np.abs(p - q).max() < 1e-5, np.abs(p - q).max()
    return t


SPHERE = os.path.join(D, "s48.vti")
run("generate", "sphere", "--size", 48, "-o", SPHERE, "-q")
check("sphere contour: linear subdivision equals vtkLinearSubdivisionFilter's", linear_vs_vtk(SPHERE, 20.5, "sphere"))
if os.path.exists(DEN):
    for iso in (37.3, 90.5):
        check(f"MRI head contour at {iso}: linear subdivision equals VTK's", linear_vs_vtk(DEN, iso, f"brain{iso}"))


def bezier_rounder():
    src = os.path.join(D, "sn.vtp")
    run("contour", SPHERE, "-o", src, "--iso", 20.5, "--normals", "average", "-q")
    dev = {}
    for scheme in ("linear", "bezier"):
        out = os.path.join(D, f"s-{scheme}.vtp")
        run("subdivide", src, "-o", out, "--levels", 2, "--scheme", scheme, "-q")
        run("check", out, "--expect-closed", "-q")
        m = read_polydata(out)
        r = np.linalg.norm(points_of(m) - 24.0, axis=1)
        dev[scheme] = np.abs(r - 20.5).max()
        assert m.GetPointData().GetArray("Normals") is not None
        assert m.GetPointData().GetArray("distance") is not None
    print(f"        max deviation from the sphere: linear {dev['linear']:.4f}, bezier {dev['bezier']:.4f} voxels")
    assert dev["bezier"] < dev["linear"], dev


check("Bezier subdivision of the sphere stays closer to it than linear, closed manifold", bezier_rounder)


def tet_volumes(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    ug = r.GetOutput()
    p = ns.vtk_to_numpy(ug.GetPoints().GetData()).astype(np.float64)
    t = ns.vtk_to_numpy(ug.GetCells().GetConnectivityArray()).reshape(-1, 4)
    a, b, c, d = (p[t[:, k]] for k in range(4))
    return ug, np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6


def tets():
    n = 12
    vti = os.path.join(D, "s12.vti")
    run("generate", "sphere", "--size", n, "-o", vti, "-q")
    t5, t8, t24 = (os.path.join(D, x) for x in ("t5.vtu", "t8.vtu", "t24.vtu"))
    run("tetrahedralize", vti, "-o", t5, "-q")
    run("subdivide", t5, "-o", t8, "-q")
    run("tetrahedralize", vti, "-o", t24, "--scheme", 24, "-q")
    ug5, v5 = tet_volumes(t5)
    ug8, v8 = tet_volumes(t8)
    ug24, v24 = tet_volumes(t24)
    assert ug8.GetNumberOfCells() == 8 * ug5.GetNumberOfCells()
    assert ug24.GetNumberOfCells() == 24 * (n - 1) ** 3
    assert ug24.GetNumberOfPoints() == n ** 3 + 3 * n * (n - 1) ** 2 + (n - 1) ** 3
    for v in (v8, v24):
        assert (v > 0).all() and abs(v.sum() - (n - 1) ** 3) < 1e-6 * (n - 1) ** 3
    out = os.path.join(D, "c24.ply")
    run("contour", t24, "-o", out, "--iso", n / 2 - 1.5, "-q")
    run("check", out, "--expect-closed", "-q")


check("tets 1 -> 8 and scheme 24: counts, positive volumes summing to the box, closed sphere contour", tets)
finish()
