"""Cell fields through the command (issue 33, item 5): a label surface's
boundary_labels and label are kept by .vtp (CellData) and .ply (face
properties) both ways, by convert between them, by subdivide (each child
face its parent's values) and listed by info. The .vtp files are read by
VTK's own reader (python3-vtk9), the .ply header by hand."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, read_polydata, report, require_vtk, run, tempdir  # noqa: E402

require_vtk()
import numpy as np  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

D = tempdir()


def label_map():
    """Three touching labels in a 12^3 uint8 .raw (x fastest)."""
    i, j, k = np.indices((12, 12, 12))
    v = (1 * (i > 3) + 2 * (j > 6) + 3 * ((i - 6) ** 2 + (k - 6) ** 2 < 9)).astype(np.uint8)
    path = os.path.join(D, "labels.raw")
    v.T.tofile(path)
    return path, ["--dims", 12, 12, 12, "--type", "uint8"]


def vtk_cells(path):
    """(triangles, {name: cell array}) of a .vtp as VTK reads it."""
    poly = read_polydata(path)
    cd = poly.GetCellData()
    conn = ns.vtk_to_numpy(poly.GetPolys().GetConnectivityArray())
    return conn.reshape(-1, 3), {cd.GetArrayName(i): ns.vtk_to_numpy(cd.GetArray(i)).copy()
                                 for i in range(cd.GetNumberOfArrays())}


def ply_face_properties(path):
    head = open(path, "rb").read().split(b"end_header\n", 1)[0].decode()
    face = head.split("element face ", 1)[1]
    return [line.split()[-1] for line in face.splitlines()[1:] if line.startswith("property float")]


def labels_through_ply_and_convert():
    raw, opts = label_map()
    vtp, ply, back = (os.path.join(D, n) for n in ("a.vtp", "a.ply", "back.vtp"))
    run("labels", raw, *opts, "--method", "discrete-mc", "-o", vtp, "-q")
    tris, fields = vtk_cells(vtp)
    assert set(fields) == {"boundary_labels", "label"} and len(np.unique(fields["boundary_labels"], axis=0)) > 2
    run("convert", vtp, "-o", ply, "-q")
    assert ply_face_properties(ply) == ["boundary_labels_0", "boundary_labels_1", "label"], ply_face_properties(ply)
    run("convert", ply, "-o", back, "-q")
    tris2, fields2 = vtk_cells(back)
    assert np.array_equal(tris2, tris)
    for name, values in fields.items():
        assert np.array_equal(fields2[name], values), name
    # labels -o .ply writes them directly, with no warning that they are dropped
    direct = os.path.join(D, "direct.ply")
    p = run("labels", raw, *opts, "--method", "discrete-mc", "-o", direct)
    assert "boundary_labels is not written" not in p.stderr, p.stderr
    assert open(direct, "rb").read() == open(ply, "rb").read()


def info_lists_cell_fields():
    raw, opts = label_map()
    vtp = os.path.join(D, "i.vtp")
    run("labels", raw, *opts, "-o", vtp, "-q")
    for path in (vtp, os.path.join(D, "i.ply")):
        if path.endswith(".ply"):
            run("convert", vtp, "-o", path, "-q")
        p = run("info", path, "--report", path + ".json")
        assert "cell field boundary_labels (2 components)" in p.stdout, p.stdout
        fields = report(path + ".json")["fields"]
        assert {"name": "boundary_labels", "components": 2, "association": "cell"} in fields, fields


def subdivide_repeats_parents():
    raw, opts = label_map()
    vtp, fine = os.path.join(D, "s.vtp"), os.path.join(D, "s_fine.vtp")
    run("labels", raw, *opts, "--per-label", "-o", vtp, "-q")
    _, fields = vtk_cells(vtp)
    run("subdivide", vtp, "-o", fine, "--levels", 1, "-q")
    _, fine_fields = vtk_cells(fine)
    for name, values in fields.items():
        assert np.array_equal(fine_fields[name], np.repeat(values, 4, axis=0)), name


check(".vtp -> .ply -> .vtp keeps boundary_labels and label (VTK reads them); labels -o .ply keeps them",
      labels_through_ply_and_convert)
check("info lists a surface's cell fields (.vtp and .ply), the report says association cell", info_lists_cell_fields)
check("subdivide gives each child face its parent's cell fields", subdivide_repeats_parents)
finish()
