"""Unstructured grid files between VTK and keymesh.

VTK (python3-vtk9) writes one mixed grid (tets, hexahedra, voxels, wedges,
pyramids, triangles, quads, a polygon; double points; point and cell arrays
of several numeric types and component counts, normals) as .vtu in every
variant its XML writer has (ascii, inline binary, appended raw and base64;
zlib or none; UInt32 or UInt64 headers; Int32 or Int64 ids; several pieces)
and as legacy .vtk (ascii and binary; file versions 4.2 and 5.1).
`keymesh convert` rewrites each as .vtu and as .vtk, and VTK reads keymesh's
files back: points must equal the input's rounded to float32, connectivity,
offsets and types must be equal, and every array must come back with its
name, component count and values rounded to float32.

Run: /usr/bin/python3 tests/vtk/test_vtu_interop.py build/keymesh
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import kmtest  # noqa: E402
from kmtest import check, finish, report, run  # noqa: E402

kmtest.require_vtk()

import numpy as np  # noqa: E402
import vtk  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

TMP = kmtest.tempdir()

# VTK cell type -> corner count; 0 = polygon (any count).
CELLS = [(vtk.VTK_TETRA, 4), (vtk.VTK_HEXAHEDRON, 8), (vtk.VTK_VOXEL, 8), (vtk.VTK_WEDGE, 6),
         (vtk.VTK_PYRAMID, 5), (vtk.VTK_TRIANGLE, 3), (vtk.VTK_QUAD, 4), (vtk.VTK_POLYGON, 0)]


def source_grid(uniform_tets=False):
    """A grid with every cell type keymesh keeps, or tets only."""
    rng = np.random.default_rng(7)
    n = 60
    pts = rng.normal(size=(n, 3)) * np.array([1.0, 1e-3, 1e4])  # doubles with bits float32 lacks
    grid = vtk.vtkUnstructuredGrid()
    p = vtk.vtkPoints()
    p.SetDataTypeToDouble()
    p.SetData(ns.numpy_to_vtk(pts, deep=True))
    grid.SetPoints(p)
    kinds = [(vtk.VTK_TETRA, 4)] if uniform_tets else CELLS
    count = 0
    for rep in range(5):
        for t, k in kinds:
            k = k or 7  # a heptagon
            ids = vtk.vtkIdList()
            for c in rng.choice(n, size=k, replace=False):
                ids.InsertNextId(int(c))
            grid.InsertNextCell(t, ids)
            count += 1

    def add(data, name, values, comps=1):
        a = ns.numpy_to_vtk(values.reshape(-1, comps) if comps > 1 else values, deep=True)
        a.SetName(name)
        data.AddArray(a)
        return a

    pd, cd = grid.GetPointData(), grid.GetCellData()
    pd.SetScalars(add(pd, "temperature", rng.normal(size=n) * 100.0))
    add(pd, "label", rng.integers(-5000, 5000, size=n).astype(np.int32))
    add(pd, "rg", rng.integers(0, 256, size=2 * n).astype(np.uint8), 2)
    add(pd, "tensor6", rng.normal(size=6 * n).astype(np.float32), 6)
    normals = rng.normal(size=(n, 3)).astype(np.float32)
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    pd.SetNormals(add(pd, "Normals", normals.ravel(), 3))
    add(cd, "cellid", np.arange(count, dtype=np.int64) * 3 + 1)
    cd.SetScalars(add(cd, "pressure", rng.normal(size=count).astype(np.float32)))
    add(cd, "flow", rng.normal(size=3 * count), 3)
    return grid


def read_vtk(path):
    ext = os.path.splitext(path)[1]
    r = vtk.vtkXMLUnstructuredGridReader() if ext == ".vtu" else vtk.vtkUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    if ext == ".vtk":
        r.ReadAllScalarsOn()
        r.ReadAllVectorsOn()
        r.ReadAllNormalsOn()
        r.ReadAllTensorsOn()
        r.ReadAllFieldsOn()
        r.Update()
    return r.GetOutput()


def arrays_of(data):
    out = {}
    for i in range(data.GetNumberOfArrays()):
        a = data.GetArray(i)
        if a is not None:
            out[a.GetName()] = ns.vtk_to_numpy(a).reshape(a.GetNumberOfTuples(), a.GetNumberOfComponents())
    return out


def topology(g):
    cells = g.GetCells()
    conn = ns.vtk_to_numpy(cells.GetConnectivityArray()).astype(np.int64)
    offs = ns.vtk_to_numpy(cells.GetOffsetsArray()).astype(np.int64)
    types = ns.vtk_to_numpy(g.GetCellTypesArray()).astype(np.int64)
    return conn, offs, types


def expect_same(reference, got, label):
    """got (keymesh's file read by VTK) holds reference's data rounded to float32."""
    assert got.GetNumberOfPoints() == reference.GetNumberOfPoints(), \
        f"{label}: {got.GetNumberOfPoints()} points, VTK read {reference.GetNumberOfPoints()}"
    assert got.GetNumberOfCells() == reference.GetNumberOfCells(), \
        f"{label}: {got.GetNumberOfCells()} cells, VTK read {reference.GetNumberOfCells()}"
    ref_pts = ns.vtk_to_numpy(reference.GetPoints().GetData()).astype(np.float32)
    got_pts = ns.vtk_to_numpy(got.GetPoints().GetData())
    assert got_pts.dtype == np.float32, f"{label}: points are {got_pts.dtype}"
    assert np.array_equal(ref_pts, got_pts), f"{label}: points differ from float32(input)"
    for a, b, what in zip(topology(reference), topology(got), ("connectivity", "offsets", "types")):
        assert np.array_equal(a, b), f"{label}: {what} differ"
    for ref_data, got_data, where in ((reference.GetPointData(), got.GetPointData(), "point"),
                                      (reference.GetCellData(), got.GetCellData(), "cell")):
        ref_arrays, got_arrays = arrays_of(ref_data), arrays_of(got_data)
        assert set(ref_arrays) == set(got_arrays), \
            f"{label}: {where} arrays {sorted(got_arrays)}, VTK read {sorted(ref_arrays)}"
        for name, ref in ref_arrays.items():
            g = got_arrays[name]
            assert g.shape == ref.shape, f"{label}: {where} array {name} shape {g.shape}, expected {ref.shape}"
            assert np.array_equal(ref.astype(np.float32), g.astype(np.float32)), \
                f"{label}: {where} array {name} values differ"
    if reference.GetPointData().GetNormals() is not None:
        n = got.GetPointData().GetNormals()
        assert n is not None and n.GetName() == "Normals", f"{label}: normals not marked"


def xml_variant(name, grid, mode, zlib, header64, id64, encode=False, pieces=1, float32_points=False):
    path = os.path.join(TMP, name + ".vtu")
    if float32_points:
        g2 = vtk.vtkUnstructuredGrid()
        g2.DeepCopy(grid)
        p = vtk.vtkPoints()
        p.SetDataTypeToFloat()
        p.DeepCopy(grid.GetPoints())
        p.SetData(ns.numpy_to_vtk(ns.vtk_to_numpy(grid.GetPoints().GetData()).astype(np.float32), deep=True))
        g2.SetPoints(p)
        grid = g2
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetInputData(grid)
    w.SetFileName(path)
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary, "appended": w.SetDataModeToAppended}[mode]()
    w.SetEncodeAppendedData(encode)
    if zlib:
        w.SetCompressorTypeToZLib()
        w.SetBlockSize(256)  # several blocks per array
    else:
        w.SetCompressorTypeToNone()
    w.SetHeaderTypeToUInt64() if header64 else w.SetHeaderTypeToUInt32()
    w.SetIdTypeToInt64() if id64 else w.SetIdTypeToInt32()
    w.SetNumberOfPieces(pieces)
    assert w.Write() == 1, f"VTK could not write {path}"
    return path


def legacy_variant(name, grid, binary, version):
    path = os.path.join(TMP, name + ".vtk")
    w = vtk.vtkUnstructuredGridWriter()
    w.SetInputData(grid)
    w.SetFileName(path)
    w.SetFileTypeToBinary() if binary else w.SetFileTypeToASCII()
    if version is not None:
        w.SetFileVersion(version)
    assert w.Write() == 1, f"VTK could not write {path}"
    return path


def converts(path):
    """keymesh convert path -> .vtu and .vtk; each read by VTK equals VTK's read of path."""
    def t():
        reference = read_vtk(path)
        assert reference.GetNumberOfCells() > 0, f"VTK read nothing from {path}"
        for ext in (".vtu", ".vtk"):
            out = path + ".keymesh" + ext
            run("convert", path, "-o", out, "-q")
            expect_same(reference, read_vtk(out), f"{os.path.basename(path)} -> {ext}")
    return t


def main():
    mixed = source_grid()
    tets = source_grid(uniform_tets=True)
    variants = []
    for mode in ("ascii", "binary", "appended"):
        for zlib in (False, True):
            for header64 in (False, True):
                for id64 in (False, True):
                    for encode in ((False, True) if mode == "appended" else (False,)):
                        name = f"{mode}-{'zlib' if zlib else 'raw'}-h{64 if header64 else 32}-id{64 if id64 else 32}"
                        name += "-base64" if encode else ""
                        variants.append(xml_variant(name, mixed, mode, zlib, header64, id64, encode))
    variants.append(xml_variant("float32-points", mixed, "appended", False, False, False, float32_points=True))
    variants.append(xml_variant("three-pieces", mixed, "appended", True, True, True, pieces=3))
    variants.append(xml_variant("tets-binary", tets, "binary", True, False, False))
    versions = [None] + [v for v in (42, 51)]
    for binary in (False, True):
        for version in versions:
            name = f"legacy-{'binary' if binary else 'ascii'}-{version or 'default'}"
            variants.append(legacy_variant(name, mixed, binary, version))
    variants.append(legacy_variant("legacy-tets", tets, True, 42))
    for path in variants:
        check(f"convert {os.path.basename(path)}", converts(path))

    def info_counts():
        path = variants[0]
        r = os.path.join(TMP, "info.json")
        p = run("info", path, "--report", r)
        j = report(r)
        ref = read_vtk(path)
        assert j["kind"] == "grid" and j["points"] == ref.GetNumberOfPoints() and j["cells"] == ref.GetNumberOfCells(), j
        types = topology(ref)[2]
        names = {vtk.VTK_TETRA: "tetra", vtk.VTK_HEXAHEDRON: "hexahedron", vtk.VTK_VOXEL: "voxel",
                 vtk.VTK_WEDGE: "wedge", vtk.VTK_PYRAMID: "pyramid", vtk.VTK_TRIANGLE: "triangle",
                 vtk.VTK_QUAD: "quad", vtk.VTK_POLYGON: "polygon"}
        expected = {names[t]: int((types == t).sum()) for t in set(types.tolist())}
        assert j["cell_types"] == expected, (j["cell_types"], expected)
        assert "unstructured grid" in p.stdout
        fields = {(f["association"], f["name"]) for f in j["fields"]}
        assert ("point", "Normals") in fields and ("cell", "cellid") in fields, fields
    check("info reports points, cells, cell types and fields of a VTK-written grid", info_counts)

    def refused():
        poly = os.path.join(TMP, "poly.vtk")
        w = vtk.vtkPolyDataWriter()
        s = vtk.vtkSphereSource()
        s.Update()
        w.SetInputData(s.GetOutput())
        w.SetFileName(poly)
        w.Write()
        p = run("convert", poly, "-o", os.path.join(TMP, "out.vtu"), expect=1)
        assert poly in p.stderr and "POLYDATA" in p.stderr, p.stderr
        assert not os.path.exists(os.path.join(TMP, "out.vtu"))
        p = run("convert", variants[0], "-o", os.path.join(TMP, "out.ply"), expect=2)
        assert "unstructured grid" in p.stderr and "surface mesh" in p.stderr, p.stderr
        broken = os.path.join(TMP, "broken.vtu")
        with open(variants[1], "rb") as f:
            data = f.read()
        with open(broken, "wb") as f:
            f.write(data[: len(data) * 2 // 3])
        p = run("convert", broken, "-o", os.path.join(TMP, "out2.vtu"), expect=1)
        assert broken in p.stderr, p.stderr
        assert not os.path.exists(os.path.join(TMP, "out2.vtu"))
    check("a POLYDATA .vtk, a cross-kind conversion and a truncated .vtu are refused by name", refused)
    finish()


if __name__ == "__main__":
    main()
