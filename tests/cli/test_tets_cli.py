"""End-to-end tests of `keymesh tetrahedralize`, `contour` on tet grids,
`subdivide` and `info` on grids: reports, exit codes and no partial outputs."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, report, run, tempdir  # noqa: E402

D = tempdir()
VTI = os.path.join(D, "s16.vti")
run("generate", "sphere", "--size", 16, "-o", VTI, "-q")


def tetrahedralize_report():
    out = os.path.join(D, "t.vtu")
    run("tetrahedralize", VTI, "-o", out, "--report", out + ".json", "-q")
    r = report(out + ".json")
    assert r["points"] == 16 ** 3 and r["cells"] == 5 * 15 ** 3, r
    assert {"total", "read", "tetrahedralize", "write"} <= set(r["seconds"]), r["seconds"]
    run("tetrahedralize", VTI, "-o", os.path.join(D, "t24.vtk"), "--scheme", 24, "--report", out + "24.json", "-q")
    r = report(out + "24.json")
    assert r["cells"] == 24 * 15 ** 3 and r["points"] == 16 ** 3 + 3 * 16 * 15 ** 2 + 15 ** 3, r


def contour_tets_report():
    out = os.path.join(D, "c.vtp")
    run("contour", os.path.join(D, "t.vtu"), "-o", out, "--iso", 6.5, "--report", out + ".json", "-q")
    r = report(out + ".json")
    for key in ("points", "cells", "threads", "seconds"):
        assert key in r, key
    assert {"total", "read", "contour", "write"} <= set(r["seconds"])
    run("check", out, "--expect-closed", "-q")
    # The same surface from the scheme-24 grid is closed too.
    run("contour", os.path.join(D, "t24.vtk"), "-o", out, "--iso", 6.5, "-q")
    run("check", out, "--expect-closed", "-q")


def subdivide_counts():
    src, out = os.path.join(D, "c.vtp"), os.path.join(D, "c2.ply")
    run("contour", VTI, "-o", src, "--iso", 6.5, "--normals", "average", "-q")
    run("subdivide", src, "-o", out, "--levels", 2, "--scheme", "bezier", "--report", out + ".json", "-q")
    r = report(out + ".json")
    assert r["cells"] == 16 * r["input_cells"], r
    run("check", out, "--expect-closed", "-q")
    run("subdivide", os.path.join(D, "t.vtu"), "-o", os.path.join(D, "t8.vtu"), "--report", out + "t.json", "-q")
    assert report(out + "t.json")["cells"] == 8 * 5 * 15 ** 3


def info_grid():
    p = run("info", os.path.join(D, "t.vtu"), "--report", os.path.join(D, "i.json"))
    r = report(os.path.join(D, "i.json"))
    assert r["kind"] == "grid" and r["cell_types"] == {"tetra": 5 * 15 ** 3}, r
    assert "tetra" in p.stdout


def errors():
    missing = os.path.join(D, "missing.vtu")
    for args, code in ((["tetrahedralize", missing, "-o", os.path.join(D, "x.vtu")], 1),
                       (["tetrahedralize", VTI, "-o", os.path.join(D, "x.vtu"), "--scheme", 6], 2),
                       (["contour", os.path.join(D, "t.vtu"), "-o", os.path.join(D, "x.vtp"), "--iso", 1,
                         "--normals", "gradient"], 2),
                       (["contour", os.path.join(D, "t.vtu"), "-o", os.path.join(D, "x.vtp"), "--iso", 1,
                         "--array", "nope"], 1),
                       (["subdivide", os.path.join(D, "t.vtu"), "-o", os.path.join(D, "x.vtu"), "--scheme",
                         "bezier"], 2),
                       (["subdivide", os.path.join(D, "c.vtp"), "-o", os.path.join(D, "x.vtu")], 2),
                       (["tetrahedralize", VTI, "-o", "/nonexistent-dir/x.vtu"], 1)):
        p = run(*args, expect=code)
        assert p.stderr.strip(), f"{args}: no message"
    bad = os.path.join(D, "bad.vtu")
    with open(bad, "w") as f:
        f.write("<VTKFile type='UnstructuredGrid'><UnstructuredGrid><Piece NumberOfPoints='3'")
    p = run("contour", bad, "-o", os.path.join(D, "y.vtp"), "--iso", 1, expect=1)
    assert "bad.vtu" in p.stderr, p.stderr
    leftovers = [f for f in os.listdir(D) if f.startswith(("x.", "y.")) or ".tmp-" in f]
    assert not leftovers, leftovers


check("tetrahedralize: report counts for schemes 5 and 24", tetrahedralize_report)
check("contour on tet grids: report keys, closed surfaces from .vtu and .vtk", contour_tets_report)
check("subdivide: 16x cells after two Bezier levels, 8x tets", subdivide_counts)
check("info on a grid: cell types and fields", info_grid)
check("bad input exits 1, bad usage 2, with a message and no output left", errors)
finish()
