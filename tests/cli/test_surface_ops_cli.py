"""End-to-end tests of `contour --coarsen/--curvature`, `quality`, `dual` and
`pipeline`: report keys, the properties each promises, and usage errors."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, report, run, tempdir  # noqa: E402

D = tempdir()
VTI = os.path.join(D, "s48.vti")
run("generate", "sphere", "--size", 48, "-o", VTI, "-q")


def coarsen_report():
    fine, coarse = os.path.join(D, "f.vtp"), os.path.join(D, "c.vtp")
    run("contour", VTI, "-o", fine, "--iso", 20.5, "-q", "--report", fine + ".json")
    run("contour", VTI, "-o", coarse, "--iso", 20.5, "--coarsen", "-q", "--report", coarse + ".json")
    f, c = report(fine + ".json"), report(coarse + ".json")
    assert c["triangles_before"] == f["cells"] and c["triangles_after"] == c["cells"] < f["cells"], c
    assert c["nonmanifold_edges"] == 0 and c["nonmanifold_vertices"] == 0, c
    run("quality", fine, "--report", fine + ".q.json")
    run("quality", coarse, "--report", coarse + ".q.json")
    qf, qc = report(fine + ".q.json"), report(coarse + ".q.json")
    for key in ("min", "median", "mean", "fraction_above_0_6", "histogram"):
        assert key in qc, key
    assert qc["median"] > qf["median"] and qc["fraction_above_0_6"] > qf["fraction_above_0_6"], (qf, qc)
    assert sum(qc["histogram"]) == qc["cells"]


def dual_counts():
    src, out = os.path.join(D, "f.vtp"), os.path.join(D, "d.obj")
    run("dual", src, "-o", out, "-q", "--report", out + ".json")
    r = report(out + ".json")
    assert r["cells"] == r["input_points"] and r["points"] == r["input_cells"], r
    # The process's peak is reported (issue 17); it holds at least the input and the output.
    mesh_mib = (os.path.getsize(src) + os.path.getsize(out)) / 2 ** 20
    assert r["peak_rss_mib"] > 0.5 * mesh_mib, (r["peak_rss_mib"], mesh_mib)
    run("check", out, "--expect-closed", "-q")
    # Formats of triangles only get each polygon as a fan, as convert writes them (issue 33).
    polygons = os.path.join(D, "d.ply")
    run("dual", src, "-o", polygons, "-q")
    for triangles_only in ("d.stl", "d.glb"):
        fanned, converted = os.path.join(D, triangles_only), os.path.join(D, "conv_" + triangles_only)
        run("dual", src, "-o", fanned, "-q")
        run("convert", polygons, "-o", converted, "-q")
        assert open(fanned, "rb").read() == open(converted, "rb").read(), triangles_only
    p = run("dual", src, "-o", os.path.join(D, "d.vtu"), expect=2)
    assert "write the dual as" in p.stderr and not os.path.exists(os.path.join(D, "d.vtu"))


def pipeline_chain():
    out = os.path.join(D, "p.vtp")
    run("pipeline", VTI, "-o", out, "--iso", 20.5, "--coarsen", "--curvature", "--subdivide", 1, "--scheme",
        "bezier", "--dual", "-q", "--report", out + ".json")
    r = report(out + ".json")
    assert {"contour", "subdivide", "dual", "write"} <= set(r["seconds"]), r["seconds"]
    run("check", out, "--expect-closed", "-q")
    p = run("info", out)
    assert "mean_curvature" in p.stdout
    run("pipeline", VTI, "-o", out, "--iso", 20.5, "--subdivide", 1, "--scheme", "bezier", "--normals", "none",
        expect=2)


def curvature_on_tets_refused():
    vtu = os.path.join(D, "t.vtu")
    run("tetrahedralize", VTI, "-o", vtu, "-q")
    p = run("contour", vtu, "-o", os.path.join(D, "x.vtp"), "--iso", 20.5, "--curvature", expect=2)
    assert "voxel grid" in p.stderr


check("contour --coarsen: report keys, fewer triangles, better quality", coarsen_report)
check("dual: F* = V, V* = F, closed; .stl and .glb as fans, equal to convert's", dual_counts)
check("pipeline: coarsen, curvature, Bezier subdivision and dual in one run", pipeline_chain)
check("--curvature on a tet grid is a usage error", curvature_on_tets_refused)
finish()
