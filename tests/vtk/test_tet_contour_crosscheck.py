"""Cross-check of `keymesh tetrahedralize` and `keymesh contour` on tet grids
against VTK (python3-vtk9), VTK reading keymesh's files with its own readers:

- the 5-tet grid of a volume: 5 (N-1)^3 tets, N^3 points, every tet of
  positive volume, volumes summing to the box, every face used by one tet
  (boundary, as many as the box's quads times two) or two (inside);
- marching tetrahedra: point and triangle counts equal vtkContour3DLinearGrid's
  (points merged) on the same .vtu, positions within 1e-4 both ways, on the
  sphere and on a real volume with non-integer isovalues; closed 2-manifold;
- VTK-written grids (.vtu ascii / binary / appended / compressed / Int64 ids /
  Float64 points, legacy .vtk ascii and binary) read by keymesh give the same
  contour as keymesh's own file."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (check, finish, nearest_distances, points_of, read_polydata, report, require_vtk, run,  # noqa
                    tempdir, triangles_of, vtk_contour)

require_vtk()
import numpy as np  # noqa: E402
import vtk  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

D = tempdir()
DEN = "/usr/share/doc/libvolpack1-dev/examples/brainsmall.den"


def read_vtu(path):
    r = vtk.vtkXMLUnstructuredGridReader() if path.endswith(".vtu") else vtk.vtkUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()


def tets_of(ug):
    conn = ns.vtk_to_numpy(ug.GetCells().GetConnectivityArray()).astype(np.int64)
    types = ns.vtk_to_numpy(ug.GetCellTypesArray())
    assert (types == vtk.VTK_TETRA).all(), "not all cells are tetrahedra"
    return conn.reshape(-1, 4)


def vtk_tet_contour(ug, iso, array):
    ug.GetPointData().SetActiveScalars(array)
    return vtk_contour(vtk.vtkContour3DLinearGrid, ug, iso, array, MergePoints=True, InterpolateAttributes=False)


def grid_checks(n):
    def t():
        vti, vtu = os.path.join(D, f"s{n}.vti"), os.path.join(D, f"t{n}.vtu")
        run("generate", "sphere", "--size", n, "-o", vti, "-q")
        run("tetrahedralize", vti, "-o", vtu, "--scheme", 5, "-q")
        ug = read_vtu(vtu)
        assert ug.GetNumberOfPoints() == n ** 3
        assert ug.GetNumberOfCells() == 5 * (n - 1) ** 3, ug.GetNumberOfCells()
        p = points_of(ug)
        t4 = tets_of(ug)
        a, b, c, d = (p[t4[:, k]] for k in range(4))
        vol = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6
        assert (vol > 0).all(), f"{(vol <= 0).sum()} tets without positive volume"
        assert abs(vol.sum() - (n - 1) ** 3) < 1e-6 * (n - 1) ** 3, vol.sum()
        faces = np.sort(np.concatenate([t4[:, [1, 2, 3]], t4[:, [0, 2, 3]], t4[:, [0, 1, 3]], t4[:, [0, 1, 2]]]), axis=1)
        _, counts = np.unique(faces, axis=0, return_counts=True)
        assert counts.max() == 2, "a face is shared by more than two tets"
        assert (counts == 1).sum() == 2 * 6 * (n - 1) ** 2, "boundary faces are not the box's"
    return t


def contour_compare(vtu, iso, array=None, name=""):
    def t():
        out = os.path.join(D, f"c{name}.vtp")
        args = ["contour", vtu, "-o", out, "--iso", iso, "-q", "--report", out + ".json"]
        if array:
            args += ["--array", array]
        run(*args)
        km = read_polydata(out)
        ug = read_vtu(vtu)
        arr = array or ug.GetPointData().GetArrayName(0)
        ref = vtk_tet_contour(ug, iso, arr)
        assert km.GetNumberOfPoints() == ref.GetNumberOfPoints(), (km.GetNumberOfPoints(), ref.GetNumberOfPoints())
        assert km.GetNumberOfCells() == ref.GetNumberOfCells(), (km.GetNumberOfCells(), ref.GetNumberOfCells())
        a, b = points_of(km), points_of(ref)
        if len(a):
            rng = np.random.default_rng(1)
            sa = rng.choice(len(a), min(len(a), 20000), replace=False)
            sb = rng.choice(len(b), min(len(b), 20000), replace=False)
            assert nearest_distances(a[sa], b).max() < 1e-4, "a keymesh point is off VTK's"
            assert nearest_distances(b[sb], a).max() < 1e-4, "a VTK point is off keymesh's"
        r = report(out + ".json")
        assert r["points"] == km.GetNumberOfPoints() and r["cells"] == km.GetNumberOfCells()
        return out
    return t


for n in (2, 9, 40):
    check(f"5-tet grid of {n}^3: counts, positive volumes summing to the box, conforming faces", grid_checks(n))

SPHERE = os.path.join(D, "t40.vtu")
check("sphere 40^3 at iso 18.5: counts and points equal vtkContour3DLinearGrid's",
      contour_compare(SPHERE, 18.5, name="sphere"))
check("sphere 40^3 at iso 19.001 (Table-1 style): counts equal VTK's", contour_compare(SPHERE, 19.001, name="t1"))


def sphere_closed():
    out = os.path.join(D, "closed.ply")
    run("contour", SPHERE, "-o", out, "--iso", 40 / 2 - 1.5, "-q")
    run("check", out, "--expect-closed", "--report", out + ".json")
    r = report(out + ".json")
    assert r["euler_characteristic"] == 2 and r["closed_manifold"], r


check("sphere 40^3 at iso N/2 - 1.5: closed 2-manifold, Euler characteristic 2", sphere_closed)

if os.path.exists(DEN):
    BRAIN = os.path.join(D, "brain.vtu")

    def brain_grid():
        run("tetrahedralize", DEN, "-o", BRAIN, "-q")

    check("tetrahedralize the MRI head (brainsmall.den)", brain_grid)
    for iso in (37.3, 90.5, 151.7):
        check(f"MRI head tets at iso {iso}: counts and points equal vtkContour3DLinearGrid's",
              contour_compare(BRAIN, iso, name=f"brain{iso}"))
else:
    print(f"note: {DEN} missing (libvolpack1-dev); real-volume tet checks not run")


def vtk_written_variants():
    ref = os.path.join(D, "t9.vtu")
    run("contour", ref, "-o", os.path.join(D, "ref.vtp"), "--iso", 3.3, "-q")
    want = points_of(read_polydata(os.path.join(D, "ref.vtp")))
    ug = read_vtu(ref)
    variants = {}
    for mode in ("ascii", "binary", "appended"):
        for comp in (False, True):
            for header64 in (False, True):
                if mode == "ascii" and (comp or header64):
                    continue
                name = f"{mode}-{'z' if comp else 'raw'}-{'h64' if header64 else 'h32'}.vtu"
                w = vtk.vtkXMLUnstructuredGridWriter()
                w.SetInputData(ug)
                w.SetFileName(os.path.join(D, name))
                {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary,
                 "appended": w.SetDataModeToAppended}[mode]()
                if not comp:
                    w.SetCompressorTypeToNone()
                if header64:
                    w.SetHeaderTypeToUInt64()
                if mode == "appended":
                    w.EncodeAppendedDataOff()
                w.Write()
                variants[name] = os.path.join(D, name)
    # Float64 points and Int64 connectivity.
    ug64 = vtk.vtkUnstructuredGrid()
    ug64.DeepCopy(ug)
    pts = vtk.vtkPoints()
    pts.SetDataTypeToDouble()
    pts.DeepCopy(ug.GetPoints())
    pts.SetData(ns.numpy_to_vtk(points_of(ug).astype(np.float64), deep=True))
    ug64.SetPoints(pts)
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetInputData(ug64)
    w.SetFileName(os.path.join(D, "f64.vtu"))
    w.Write()
    variants["f64.vtu"] = os.path.join(D, "f64.vtu")
    for binary in (False, True):
        name = f"legacy-{'bin' if binary else 'ascii'}.vtk"
        lw = vtk.vtkUnstructuredGridWriter()
        lw.SetInputData(ug)
        lw.SetFileName(os.path.join(D, name))
        if binary:
            lw.SetFileTypeToBinary()
        if hasattr(lw, "SetFileVersion") and not binary:
            lw.SetFileVersion(42)
        lw.Write()
        variants[name] = os.path.join(D, name)
    for name, path in variants.items():
        out = os.path.join(D, f"v-{name}.vtp")
        run("contour", path, "-o", out, "--iso", 3.3, "-q")
        got = points_of(read_polydata(out))
        assert got.shape == want.shape, f"{name}: {got.shape} points, want {want.shape}"
        # Legacy ASCII holds 6 significant digits of the samples; the others hold them exactly.
        tol = 1e-3 if name == "legacy-ascii.vtk" else 1e-6
        err = np.abs(np.sort(got, axis=0) - np.sort(want, axis=0)).max()
        assert err < tol, f"{name}: points differ by {err}"


check("VTK-written .vtu/.vtk variants read by keymesh give the same contour", vtk_written_variants)


def keymesh_legacy_read_by_vtk():
    out = os.path.join(D, "k.vtk")
    run("tetrahedralize", os.path.join(D, "s9.vti"), "-o", out, "-q")
    ug = read_vtu(out)
    assert ug.GetNumberOfCells() == 5 * 8 ** 3 and ug.GetNumberOfPoints() == 9 ** 3
    assert ug.GetPointData().GetArray("distance") is not None


check("keymesh's legacy .vtk is read by VTK", keymesh_legacy_read_by_vtk)
finish()
